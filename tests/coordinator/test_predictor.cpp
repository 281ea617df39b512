// The interface predictors (coordinator/src/coupling/explicit.cpp, docs/coupling.md): the displacement the
// fluid is handed for the window's end, from the structure's state at its start. Reference: a motion of
// constant acceleration, d(t) = d0 + v0 t + a t^2 / 2, sampled at the ends of two windows of different
// lengths. "quadratic" (second order) must predict it exactly, displacement and velocity (tolerance 1e-12
// relative: round-off), "linear" (first order) misses the displacement by a dt^2 / 2 exactly and hands over
// the last velocity; the first window, with no earlier one, falls back to linear. Every pair handed over is
// one the structure can answer with: d - d_n = dt (v_n + v) / 2 (a review found the quadratic one was not).
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "sphfsi/coordinator/coupling.hpp"

using sphfsi::coordinator::InterfaceState;
using sphfsi::coordinator::predict;
using sphfsi::protocol::F64Array;

namespace {

constexpr double d0 = 0.01, v0 = -0.3, a = 2.5;
double position(double t) { return d0 + v0 * t + 0.5 * a * t * t; }
double velocity(double t) { return v0 + a * t; }

// One vertex, moving along x only, at time t after a window of length dt_prev (0: none yet).
InterfaceState state_at(double t, double dt_prev) {
    InterfaceState s;
    s.displacement = F64Array::zeros(1, 2);
    s.velocity = F64Array::zeros(1, 2);
    s.previous_displacement = F64Array::zeros(1, 2);
    s.displacement(0, 0) = position(t);
    s.velocity(0, 0) = velocity(t);
    s.previous_displacement(0, 0) = position(t - dt_prev);
    s.previous_dt = dt_prev;
    return s;
}

struct Prediction {
    double d, v;
};

Prediction predicted(const char* kind, const InterfaceState& s, double dt) {
    F64Array d, v;
    predict(kind, s, dt, d, v);
    if (std::string(kind) != "none")  // "none" keeps d_n and v_n: the structure standing where it is
        CHECK(d(0, 0) - s.displacement(0, 0) == doctest::Approx(0.5 * dt * (s.velocity(0, 0) + v(0, 0))).scale(0).epsilon(1e-12));
    return {d(0, 0), v(0, 0)};
}

// Relative, unlike doctest's default Approx, which adds 1 to the scale (an absolute 1e-12 here).
doctest::Approx near(double x, double rel) { return doctest::Approx(x).scale(0).epsilon(rel); }

}  // namespace

TEST_SUITE("predictor") {
    TEST_CASE("quadratic is exact for a constant acceleration over unequal windows; linear is first order") {
        const double t = 0.2;
        for (double dt_prev : {1e-3, 2e-3, 0.5e-3})
            for (double dt : {1e-3, 3e-3}) {
                CAPTURE(dt_prev);
                CAPTURE(dt);
                const InterfaceState s = state_at(t, dt_prev);
                const Prediction q = predicted("quadratic", s, dt), l = predicted("linear", s, dt), n = predicted("none", s, dt);
                CHECK(q.d == near(position(t + dt), 1e-12));
                CHECK(q.v == near(velocity(t + dt), 1e-12));
                CHECK(position(t + dt) - l.d == near(0.5 * a * dt * dt, 1e-6));
                CHECK(l.v == s.velocity(0, 0));
                CHECK(n.d == position(t));
                CHECK(n.v == s.velocity(0, 0));
            }
    }

    TEST_CASE("the first window has no earlier one: quadratic falls back to linear") {
        const InterfaceState s = state_at(0.0, 0.0);
        CHECK(predicted("quadratic", s, 1e-3).d == predicted("linear", s, 1e-3).d);
        CHECK(predicted("quadratic", s, 1e-3).v == predicted("linear", s, 1e-3).v);
    }
}
