#pragma once
// Writes a whole file so that a reader, or a kill at any moment, sees the old file or the new one, never a
// part of the new one: the bytes go to FILE.tmp, which is then renamed over FILE.
#include <filesystem>
#include <string_view>

namespace sphfsi::coordinator {

// Throws std::runtime_error "cannot write WHAT FILE.tmp" if the bytes could not all be written.
void replace_file(const std::filesystem::path& file, std::string_view bytes, std::string_view what);

// A resume's copy of an interrupted run's file (FILE.resuming), which takes the resumed run and replaces FILE
// only once the run has passed the last time FILE holds: until then FILE holds more than the copy, and a
// resume that stops must leave it as it was (Recorder, Watchpoints).
class ResumeCopy {
public:
    void begin(const std::filesystem::path& file);  // FILE.resuming from now on
    void holds(double t) { if (t > end_) end_ = t; }  // FILE holds time t (NaN is ignored)
    bool pending() const { return !copy_.empty(); }
    const std::filesystem::path& path() const { return copy_; }
    double end() const { return end_; }
    // A copy whose rename failed is not tried again (it was, and each failure was logged twice).
    bool caught_up(double t) const { return pending() && !rename_failed_ && t >= end_ * (1 - 1e-12); }
    bool rename_failed() const { return rename_failed_; }
    // Renames the copy over FILE (an open handle follows it); throws std::runtime_error naming both if it cannot.
    void replace(const std::filesystem::path& file);
    // Removes the copy, FILE stays; except a copy whose rename failed, which holds the whole run and is kept
    // where it is (it was removed as if the run had stopped short: a review, 2026-11-28).
    void abandon();

private:
    std::filesystem::path copy_;
    double end_ = 0.0;
    bool rename_failed_ = false;
};

}  // namespace sphfsi::coordinator
