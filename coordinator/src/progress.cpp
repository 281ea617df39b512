#include "sphfsi/coordinator/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace sphfsi::coordinator {
using Clock = std::chrono::steady_clock;

ProgressDisplay::ProgressDisplay(double t0, double t_end, bool quiet, std::uint64_t steps0)
    : t0_(t0), t_end_(t_end), tty_(::isatty(STDERR_FILENO) != 0), quiet_(quiet), start_(Clock::now()), last_(start_),
      steps0_(steps0) {}

void ProgressDisplay::update(double t, std::uint64_t steps) {
    steps_ = steps;
    if (quiet_) return;
    auto now = Clock::now();
    double since = std::chrono::duration<double>(now - last_).count();
    if (since < (tty_ ? 0.25 : 10.0)) return;
    last_ = now;
    double wall = std::chrono::duration<double>(now - start_).count();
    double done = (t - t0_) / (t_end_ - t0_);
    double eta = done > 0 ? wall * (1 - done) / done : 0;
    char line[200];
    std::snprintf(line, sizeof line, "t = %.5g s  %5.1f %%  %.0f steps/s  elapsed %.0f s  ETA %.0f s", t, 100 * done,
                  wall > 0 ? static_cast<double>(steps - steps0_) / wall : 0.0, wall, eta);
    if (tty_) {
        std::fprintf(stderr, "\r%-78s", line);
        drawn_ = true;
    } else {
        std::fprintf(stderr, "progress: %s\n", line);
    }
    std::fflush(stderr);
}

void ProgressDisplay::finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
}

}  // namespace sphfsi::coordinator
