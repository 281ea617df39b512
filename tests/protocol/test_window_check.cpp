// protocol::check_window: the ADVANCE rule of docs/protocol.md §3 that every solver applies (a window starts
// at the solver's time to 1e-9 x max(|now|, dt); t is finite and the length a finite number > 0).
#include <doctest/doctest.h>

#include <limits>
#include <string>

#include "sphfsi/protocol/solver.hpp"

using namespace sphfsi::protocol;

namespace {
AdvanceRequest window(double t, double dt) {
    AdvanceRequest r;
    r.t = t;
    r.dt = dt;
    return r;
}

// The code the check throws, "" when it accepts the window.
std::string verdict(double t, double dt, double now) {
    try {
        check_window(window(t, dt), now, "solver");
    } catch (const SolverError& e) {
        return e.code();
    }
    return "";
}
}  // namespace

TEST_CASE("check_window accepts a window at the solver's time, within round-off") {
    CHECK(verdict(0.0, 1e-4, 0.0) == "");
    CHECK(verdict(0.3 + 1e-12, 1e-4, 0.3) == "");    // 3.3e-12 relative to now: summed window lengths
    CHECK(verdict(5e-14, 1e-4, 0.0) == "");          // at t = 0 the tolerance is relative to dt (1e-13 here)
}

TEST_CASE("check_window refuses a window that starts elsewhere with bad_state, naming both times") {
    CHECK(verdict(0.5, 1e-3, 0.0) == "bad_state");
    CHECK(verdict(2e-13, 1e-4, 0.0) == "bad_state");  // beyond 1e-9 x dt at t = 0
    CHECK(verdict(0.3 + 1e-9, 1e-4, 0.3) == "bad_state");
    try {
        check_window(window(0.25, 1e-3), 0.125, "fluid");
        FAIL("no error");
    } catch (const SolverError& e) {
        const std::string m = e.what();
        CHECK(m.find("fluid") != std::string::npos);
        CHECK(m.find("0.25") != std::string::npos);
        CHECK(m.find("0.125") != std::string::npos);
    }
}

TEST_CASE("check_window refuses a start that is not finite, or a length that is not a finite number > 0, as bad_message") {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    CHECK(verdict(0.0, 0.0, 0.0) == "bad_message");
    CHECK(verdict(0.0, -1e-3, 0.0) == "bad_message");
    CHECK(verdict(0.0, nan, 0.0) == "bad_message");
    CHECK(verdict(0.0, inf, 0.0) == "bad_message");
    CHECK(verdict(nan, 1e-3, 0.0) == "bad_message");
    CHECK(verdict(inf, 1e-3, 0.0) == "bad_message");
}

TEST_CASE("check_window refuses a window too short to move the clock at its start, as bad_message") {
    // At t = 1e15 s a double's spacing is 0.125 s: t + 1 ms is t, and the fluid answered such a window with
    // no step at all (substeps 0; a review, 2026-11-28).
    CHECK(verdict(1e15, 1e-3, 1e15) == "bad_message");
    CHECK(verdict(1.0, 1e-17, 1.0) == "bad_message");
    CHECK(verdict(1e15, 0.25, 1e15) == "");
    CHECK(verdict(0.0, 1e-300, 0.0) == "");
}

TEST_CASE("a solver whose clock is not finite accepts no window, and no time is the same instant as infinity") {
    // |t - inf| <= 1e-9 x inf held for every finite t: a structure resumed from a state at t = inf accepted
    // every ADVANCE and its run completed (a review, 2026-11-27).
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    CHECK(verdict(0.0, 1e-3, inf) == "bad_state");
    CHECK(verdict(0.0, 1e-3, nan) == "bad_state");
    CHECK_FALSE(same_instant(0.5, inf, 1e-3));
    CHECK_FALSE(same_instant(inf, inf, 1e-3));
    CHECK_FALSE(same_instant(nan, 0.5, 1e-3));
    CHECK(same_instant(0.5, 0.5, 0.0));
}
