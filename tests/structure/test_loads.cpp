// Time factors of the scene's prescribed loads (History): the value at an instant and the mean over a step.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "sphfsi/structure/config.hpp"

using sphfsi::structure::History;

namespace {
// The midpoint rule on 200,000 intervals: the factors here have at most two kinks inside [t0, t1], so its
// error is below 1e-5 of the mean (a kink costs at most one interval's share).
double midpoint_mean(const History& h, double t0, double t1) {
    const int n = 200000;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += h.factor(t0 + (i + 0.5) * (t1 - t0) / n);
    return sum / n;
}
}  // namespace

TEST_SUITE("loads") {
TEST_CASE("a load's mean factor over a step is its integral over the step, switches and kinks included") {
    History constant;
    constant.start_time = 0.3;
    constant.end_time = 0.35;
    History ramp;
    ramp.kind = History::Kind::Ramp;
    ramp.ramp_time = 0.2;
    ramp.start_time = 0.1;
    ramp.end_time = 0.6;
    History sine;
    sine.kind = History::Kind::Sine;
    sine.frequency = 7.0;
    sine.phase = 0.4;
    sine.start_time = 0.05;
    for (const History* h : {&constant, &ramp, &sine})
        for (const auto [t0, t1] : {std::pair{0.0, 1.0}, {0.28, 0.32}, {0.32, 0.34}, {0.34, 0.4}, {0.25, 0.31}, {0.58, 0.7}, {0.7, 0.8}})
            CHECK(h->mean_factor(t0, t1) == doctest::Approx(midpoint_mean(*h, t0, t1)).scale(1.0).epsilon(1e-5));
    // Exact values: the pulse of 0.05 s has mean 0.05 / 0.1 over (0.28, 0.38) and 0 outside it.
    CHECK(constant.mean_factor(0.28, 0.38) == doctest::Approx(0.5).epsilon(1e-12));
    CHECK(constant.mean_factor(0.35, 0.4) == 0.0);
    CHECK(constant.mean_factor(0.2, 0.3) == 0.0);
    // The ramp from 0.1 to 0.3 averages 1/2 over its rise.
    CHECK(ramp.mean_factor(0.1, 0.3) == doctest::Approx(0.5).epsilon(1e-12));
}
}
