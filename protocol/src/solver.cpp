#include "sphfsi/protocol/solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace sphfsi::protocol {

std::string seconds(double t) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.17g s", t);  // every digit: a refusal may be 1e-9 away
    return buf;
}

std::optional<std::uint32_t> substep_count(double count) {
    if (!(count <= std::numeric_limits<std::uint32_t>::max())) return std::nullopt;
    return static_cast<std::uint32_t>(count);
}

std::optional<std::uint32_t> substeps_to_cover(double window, double step) {
    return substep_count(std::max(1.0, std::ceil(window / step * (1.0 - 1e-12))));
}

bool same_instant(double t, double expected, double dt) {
    // A clock at infinity is at no instant: |t - inf| <= 1e-9 inf would hold for every finite t.
    if (!std::isfinite(t) || !std::isfinite(expected)) return false;
    return std::abs(t - expected) <= 1e-9 * std::max(std::abs(expected), dt);
}

void check_window(const AdvanceRequest& request, double now, const std::string& who) {
    if (!std::isfinite(request.t))
        throw SolverError("bad_message", who + ": ADVANCE t = " + seconds(request.t) + " is not a finite time");
    if (!(request.dt > 0.0) || !std::isfinite(request.dt))
        throw SolverError("bad_message", who + ": ADVANCE dt = " + seconds(request.dt) +
                                             " is not a finite window length > 0");
    // Far from t = 0 a double's spacing outgrows a short window (0.125 s at t = 1e15 s): such a window would
    // end where it starts, and no step could be taken in it.
    if (!(request.t + request.dt > request.t))
        throw SolverError("bad_message", who + ": ADVANCE dt = " + seconds(request.dt) + " at t = " + seconds(request.t) +
                                             " does not move the clock (a double's spacing there is " +
                                             seconds(std::nextafter(request.t, INFINITY) - request.t) + ")");
    if (!same_instant(request.t, now, request.dt))
        throw SolverError("bad_state", who + ": ADVANCE starts at t = " + seconds(request.t) + " but the " + who +
                                           " is at t = " + seconds(now));
}

}  // namespace sphfsi::protocol
