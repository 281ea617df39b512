#pragma once
// One run at a time per output directory. Two runs, or two `--resume`s, writing the same record.h5 would
// corrupt it, and a resume that copies the history while another writes it would lose it. The lock is an
// flock on DIR/.lock held for the run's lifetime: the kernel releases it when the process ends, however it
// ends (kill -9 included), so a stale lock file never blocks a later run.
#include <filesystem>

namespace sphfsi::coordinator {

class DirLock {
public:
    // Throws std::runtime_error naming the directory and the pid of the run that holds it.
    explicit DirLock(const std::filesystem::path& dir);
    ~DirLock();
    DirLock(const DirLock&) = delete;
    DirLock& operator=(const DirLock&) = delete;

private:
    int fd_ = -1;
};

}  // namespace sphfsi::coordinator
