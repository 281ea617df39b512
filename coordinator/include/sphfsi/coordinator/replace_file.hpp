#pragma once
// Writes a whole file so that a reader, or a kill at any moment, sees the old file or the new one, never a
// part of the new one: the bytes go to FILE.tmp, which is then renamed over FILE.
#include <filesystem>
#include <string_view>

namespace sphfsi::coordinator {

// Throws std::runtime_error "cannot write WHAT FILE.tmp" if the bytes could not all be written.
void replace_file(const std::filesystem::path& file, std::string_view bytes, std::string_view what);

}  // namespace sphfsi::coordinator
