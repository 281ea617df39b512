#pragma once
// One live line on a terminal (sim time, % done, steps/s, ETA); plain periodic lines otherwise,
// so logs of unattended runs stay readable.
#include <chrono>
#include <cstdint>
#include <string>

namespace sphfsi::coordinator {

class ProgressDisplay {
public:
    // `steps0`: steps taken before this process (a resumed run), left out of the rate.
    ProgressDisplay(double t0, double t_end, bool quiet, std::uint64_t steps0 = 0);
    void update(double t, std::uint64_t steps);
    void finish();

private:
    double t0_, t_end_;
    bool tty_, quiet_;
    std::chrono::steady_clock::time_point start_, last_;
    std::uint64_t steps0_, steps_ = 0;
    bool drawn_ = false;
};

}  // namespace sphfsi::coordinator
