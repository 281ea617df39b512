// Order of accuracy of the time integrators, measured the way a convergence study does: the same dam break
// (dp = 1 cm, WCSPH, integrated densities, no viscosity, no density diffusion, no pressure clamp, so that
// every term is smooth) over 0.1 s in N = 800 and 2N fixed steps, each compared with 16N steps (whose own
// error is 1/256 of the coarse run's at second order). The largest error of a method of order p falls by
// 2^p when the step halves: 4 for velocity Verlet and the predictor-corrector, 2 for semi-implicit Euler.
// Measured 2026-11-27, ratios of the position and density errors: velocity Verlet 3.94 and 3.98,
// predictor-corrector 3.75 and 3.84, semi-implicit Euler 2.15 and 2.66 (its densities are ahead of its
// positions before the asymptotic range). Tolerance: at least 3.3 for second order, 1.5 - 2.7 (positions)
// and 1.5 - 3.0 (densities) for first order, which tells the two apart with room for that pre-asymptotic
// spread. A review had found velocity Verlet at 2.20 (position error 10 times today's at N = 400) when it
// took each step's density rate at the start positions alone.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "run_helpers.hpp"
#include "scenes.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;

namespace {

// Fluid positions and densities by particle id after `steps` equal steps over `duration`.
struct Snapshot {
    std::vector<double> x, y, rho;
};

Snapshot run(const Value& config, double duration, unsigned steps) {
    auto solver = start(config);
    sphfsi::protocol::Progress progress;
    sphfsi::protocol::AdvanceRequest request;
    request.t = 0.0;
    request.dt = duration;
    request.substeps = steps;
    solver->advance(request, progress);
    const auto& P = solver->simulation().particles();
    Snapshot s;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        const auto k = static_cast<std::size_t>(P.id[i]);
        if (k >= s.x.size()) {
            s.x.resize(k + 1);
            s.y.resize(k + 1);
            s.rho.resize(k + 1);
        }
        s.x[k] = P.x[i][0];
        s.y[k] = P.x[i][1];
        s.rho[k] = P.rho[i];
    }
    return s;
}

// Largest position and density differences between two snapshots of the same particles.
std::pair<double, double> difference(const Snapshot& a, const Snapshot& b) {
    REQUIRE(a.x.size() == b.x.size());
    double dx = 0.0, drho = 0.0;
    for (std::size_t k = 0; k < a.x.size(); ++k) {
        dx = std::max(dx, std::hypot(a.x[k] - b.x[k], a.y[k] - b.y[k]));
        drho = std::max(drho, std::abs(a.rho[k] - b.rho[k]));
    }
    return {dx, drho};
}

// The error ratios (positions, densities) when the step halves from duration / n.
std::pair<double, double> ratios(const std::string& integrator, unsigned n) {
    const Value config = with(dam_break(0.01), {{"pressure.model", "wcsph"},
                                                {"pressure.clamp_negative", false},
                                                {"density.method", "continuity"},
                                                {"density.diffusion", "none"},
                                                {"viscosity.model", "none"},
                                                {"boundary.model", "adami"},
                                                {"time.integrator", integrator},
                                                {"threads", 1}});
    const double duration = 0.1;
    const Snapshot reference = run(config, duration, 16 * n);
    const auto coarse = difference(run(config, duration, n), reference);
    const auto fine = difference(run(config, duration, 2 * n), reference);
    const std::pair<double, double> r{coarse.first / fine.first, coarse.second / fine.second};
    std::printf("%s: N = %u, 2N: position error %.3e, %.3e (ratio %.2f); density error %.3e, %.3e (ratio %.2f)\n",
                integrator.c_str(), n, coarse.first, fine.first, r.first, coarse.second, fine.second, r.second);
    return r;
}

}  // namespace

TEST_SUITE("integrator_order") {
    TEST_CASE("velocity Verlet is second order with integrated densities") {
        const auto [position, density] = ratios("velocity_verlet", 800);
        CHECK(position >= 3.3);
        CHECK(density >= 3.3);
    }

    TEST_CASE("the predictor-corrector is second order") {
        const auto [position, density] = ratios("predictor_corrector", 800);
        CHECK(position >= 3.3);
        CHECK(density >= 3.3);
    }

    TEST_CASE("semi-implicit Euler is first order") {
        const auto [position, density] = ratios("symplectic_euler", 800);
        CHECK(position >= 1.5);
        CHECK(position <= 2.7);
        CHECK(density >= 1.5);
        CHECK(density <= 3.0);
    }
}
