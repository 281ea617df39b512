#include "sphfsi/coordinator/replace_file.hpp"

#include <cerrno>
#include <fstream>
#include <system_error>
#include <stdexcept>
#include <string>

namespace sphfsi::coordinator {

void replace_file(const std::filesystem::path& file, std::string_view bytes, std::string_view what) {
    auto tmp = file;
    tmp += ".tmp";
    {
        errno = 0;
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.close();  // a full disk may show only here, as the last buffer is written
        if (!out) {
            // The cause (a full disk, no permission) and no half-written file left on that disk: both were
            // missing (a review, 2026-11-28).
            const int cause = errno;
            std::error_code ignored;
            if (std::filesystem::is_regular_file(tmp, ignored)) std::filesystem::remove(tmp, ignored);
            throw std::runtime_error("cannot write " + std::string(what) + " " + tmp.string() +
                                     (cause ? " (" + std::generic_category().message(cause) + ")" : std::string()));
        }
    }
    std::filesystem::rename(tmp, file);
}

void ResumeCopy::begin(const std::filesystem::path& file) {
    copy_ = file;
    copy_ += ".resuming";
}

void ResumeCopy::replace(const std::filesystem::path& file) {
    std::error_code ec;
    std::filesystem::rename(copy_, file, ec);
    if (ec) {
        rename_failed_ = true;
        throw std::runtime_error("cannot rename the resumed run's copy " + copy_.string() + " over " + file.string() +
                                 ": " + ec.message());
    }
    copy_.clear();
}

void ResumeCopy::abandon() {
    if (!rename_failed_) std::filesystem::remove(copy_);
    copy_.clear();
}

}  // namespace sphfsi::coordinator
