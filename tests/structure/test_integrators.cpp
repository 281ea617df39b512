// Time integrators, run through FrameDynamics::step on a cantilever started in one natural mode.
// Because the schemes are linear and M, K are fixed, the discrete motion stays in that mode, so the
// structure behaves exactly as the single-DOF test equation q'' + omega^2 q = 0 the schemes are analysed
// on; q, q' and q'' are read back with the mass-normalized mode shape (q = phi^T M u).
#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

#include "scenes.hpp"
#include "sphfsi/structure/frame_dynamics.hpp"

using namespace structure_test;
using namespace sphfsi::structure;

namespace {
constexpr double pi = std::numbers::pi;

Value mode_scene(const char* integrator, double rho_inf = 0.9, int n = 10, bool energy_check = true) {
    Value s = beam(n);
    // The amplification matrix is measured from states set by hand, whose energy the initial state's baseline
    // knows nothing of (FrameDynamics::check_energy).
    if (!energy_check) set(s, "failure.max_energy_created", Value(0.0));
    set(s, "time.integrator", Value(integrator));
    set(s, "time.rho_inf", Value(rho_inf));
    set(s, "initial.mode", Value(1));
    set(s, "initial.mode_amplitude", Value(0.01));
    return s;
}

struct Modal {
    double q, qd, qdd;
};
Modal modal(const FrameDynamics& f, int mode = 0) {
    const Vector Mphi = f.mass() * f.modes().shapes.col(mode);
    return {Mphi.dot(f.state().u), Mphi.dot(f.state().v), Mphi.dot(f.state().a)};
}

// Amplification matrix of one step of size h on mode 1: columns are the modal (q, q', q'') after one
// step from unit initial values, each set up as a full-DOF state along the mode shape.
Eigen::Matrix3d amplification(FrameDynamics& f, double h) {
    const Vector phi = f.modes().shapes.col(0);
    Eigen::Matrix3d A;
    for (int j = 0; j < 3; ++j) {
        State& s = f.state();
        s.t = 0;
        s.u = (j == 0 ? 1.0 : 0.0) * phi;
        s.v = (j == 1 ? 1.0 : 0.0) * phi;
        s.a = (j == 2 ? 1.0 : 0.0) * phi;
        f.step(h, Vector());
        const Modal m = modal(f);
        A.col(j) << m.q, m.qd, m.qdd;
    }
    return A;
}
double spectral_radius(const Eigen::Matrix3d& A) { return Eigen::EigenSolver<Eigen::Matrix3d>(A).eigenvalues().cwiseAbs().maxCoeff(); }

// State error |(q, q'/w) - exact| after one period, started from the mode shape at rest. (The error
// of q alone at a peak is second order in the phase error and would show a spurious 4th order.)
double period_error(const char* integrator, double rho_inf, int steps_per_period) {
    FrameDynamics f(config(mode_scene(integrator, rho_inf)));
    const double w = f.modes().omega(0), T = 2 * pi / w, q0 = modal(f).q;
    for (int k = 0; k < steps_per_period; ++k) f.step(T / steps_per_period, Vector());
    const Modal m = modal(f);
    return std::hypot(m.q - q0 * std::cos(w * T), m.qd / w + q0 * std::sin(w * T));
}
}  // namespace

TEST_SUITE("integrators") {
TEST_CASE("Newmark average acceleration: total energy drift < 1e-6 over 100 periods (undamped)") {
    // Plucked start: static shape under a tip load, released at t = 0; it excites every mode. The
    // trapezoidal rule conserves the discrete energy of linear undamped systems exactly, so any drift
    // is round-off; 1e-6 is the acceptance bound.
    Value s = beam(10);
    set(s, "time.integrator", Value("newmark"));
    set(s, "initial.preload", Value(Value::Array{point_load(L, 0, 0, -1000.0)}));
    FrameDynamics f(config(s));
    const double T = 2 * pi / f.modes().omega(0);
    const auto e0 = f.energies();
    const double E0 = e0.kinetic + e0.strain;
    CHECK(e0.kinetic == 0.0);
    double drift = 0;
    const int per_period = 40;
    for (int k = 0; k < 100 * per_period; ++k) {
        f.step(T / per_period, Vector());
        const auto e = f.energies();
        drift = std::max(drift, std::abs(e.kinetic + e.strain - E0) / E0);
    }
    MESSAGE("largest relative energy drift over 100 periods: " << drift);
    CHECK(drift < 1e-6);
    CHECK(f.energies().kinetic > 0.01 * E0);  // it really is vibrating
}

TEST_CASE("backward Euler: amplitude decays by 1/sqrt(1 + (omega dt)^2) per step") {
    // BE on q'' + w^2 q = 0: [1 -W; W 1] x_{n+1} = x_n for x = (q, q'/w), W = w dt; a scaled rotation,
    // so |x| shrinks by exactly (1 + W^2)^-1/2 per step. Acceptance: within 1 %.
    for (double W : {0.05, 0.3, 1.0, 4.0}) {
        FrameDynamics f(config(mode_scene("backward_euler")));
        const double w = f.modes().omega(0);
        auto amplitude = [&] {
            const Modal m = modal(f);
            return std::hypot(m.q, m.qd / w);
        };
        const double A0 = amplitude();
        const int steps = 50;
        for (int k = 0; k < steps; ++k) f.step(W / w, Vector());
        const double per_step = std::pow(amplitude() / A0, 1.0 / steps);
        const double want = 1.0 / std::sqrt(1.0 + W * W);
        MESSAGE("W = " << W << ": per-step decay " << per_step << " vs " << want);
        CHECK(rel(per_step, want) <= 0.01);
    }
}

TEST_CASE("generalized-alpha: spectral radius -> rho_inf at large omega dt, ~1 at small") {
    // Chung & Hulbert (1993): with their optimal alpha_m, alpha_f, beta, gamma, the spectral radius of
    // the amplification matrix tends to rho_inf as omega dt -> infinity. At omega dt = 1e4 the
    // remainder is O(1/(omega dt)); acceptance: within 0.01 of rho_inf.
    for (double rho : {0.0, 0.5, 0.8, 1.0}) {
        FrameDynamics f(config(mode_scene("generalized_alpha", rho, 10, false)));
        const double w = f.modes().omega(0);
        const double high = spectral_radius(amplification(f, 1e4 / w));
        const double low = spectral_radius(amplification(f, 0.01 / w));
        MESSAGE("rho_inf = " << rho << ": spectral radius " << high << " at omega dt = 1e4, " << low << " at 0.01");
        CHECK(std::abs(high - rho) <= 0.01);
        CHECK(low == doctest::Approx(1.0).epsilon(1e-5));
    }
    // Newmark average acceleration never damps; backward Euler annihilates high frequencies.
    FrameDynamics nm(config(mode_scene("newmark", 0.9, 10, false)));
    CHECK(spectral_radius(amplification(nm, 1e4 / nm.modes().omega(0))) == doctest::Approx(1.0).epsilon(1e-9));
    FrameDynamics be(config(mode_scene("backward_euler", 0.9, 10, false)));
    CHECK(spectral_radius(amplification(be, 1e4 / be.modes().omega(0))) <= 1e-3);
}

TEST_CASE("order of accuracy: generalized-alpha and Newmark second order, backward Euler first") {
    // Halving dt divides the error after one period by 2^p. Acceptance: p within 0.15 of 2 (or of 1).
    // Backward Euler needs finer steps to be in its asymptotic range (its error exp(-pi W) per period
    // is far from linear in W = omega dt at 40 steps per period).
    auto order = [](const char* integrator, double rho, int steps) {
        const double e1 = period_error(integrator, rho, steps), e2 = period_error(integrator, rho, 2 * steps);
        return std::log2(e1 / e2);
    };
    const double p_ga = order("generalized_alpha", 0.8, 40), p_nm = order("newmark", 1.0, 40);
    const double p_be = order("backward_euler", 1.0, 400);
    MESSAGE("observed orders: generalized_alpha " << p_ga << ", newmark " << p_nm << ", backward_euler " << p_be);
    CHECK(std::abs(p_ga - 2.0) <= 0.15);
    CHECK(std::abs(p_nm - 2.0) <= 0.15);
    CHECK(std::abs(p_be - 1.0) <= 0.15);
}

TEST_CASE("dt accuracy limit: steps_per_period of the highest resolved mode, stricter for backward Euler") {
    Value s = beam(10);
    set(s, "time.resolved_modes", Value(2));
    set(s, "time.steps_per_period", Value(25.0));
    const FrameDynamics ga(config(s));
    CHECK(ga.dt_accuracy() == doctest::Approx(2 * pi / ga.modes().omega(1) / 25.0).epsilon(1e-12));
    set(s, "time.integrator", Value("backward_euler"));
    set(s, "time.max_numerical_damping", Value(0.01));
    const FrameDynamics be(config(s));
    const double W = be.dt_accuracy() * be.modes().omega(1);
    CHECK(std::log1p(W * W) / (2 * std::atan(W)) == doctest::Approx(0.01).epsilon(1e-9));
}
}
