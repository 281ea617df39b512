#include "sphfsi/coordinator/replace_file.hpp"

#include <fstream>
#include <stdexcept>
#include <string>

namespace sphfsi::coordinator {

void replace_file(const std::filesystem::path& file, std::string_view bytes, std::string_view what) {
    auto tmp = file;
    tmp += ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.close();  // a full disk may show only here, as the last buffer is written
        if (!out) throw std::runtime_error("cannot write " + std::string(what) + " " + tmp.string());
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
