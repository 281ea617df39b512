// Dam break: the thesis's water column, 0.1 m wide (a) and 0.2 m high (2a, so n^2 = 2), released at t = 0
// against the left wall of a 0.5 m tank, dyed in two halves. Reference: surge-front position
// Z = x_front / a against T = t sqrt(2 g / a), Martin & Moyce (1952), Tables 2 and 6 (n^2 = 2), read from
// data/martin_moyce_1952_front_n2_2.csv. The front is the largest x of a fluid particle centre plus dp/2
// (the particle's own extent). Resolution: dp = a/40 (4538 particles), so the suite stays fast.
//
// Tolerance: 10 % for T <= 2.5 as the issue asks, but the experiment lags every simulation released at
// once from T ~ 0.8 on (Lethe, DualSPHysics and VOF results show the same lead), which the issue puts down
// to the gate's removal. We do not shift or scale time. A modelled gate lifted at 0.5 - 8 m/s
// ([fluid.gate], docs/validation.md) does not remove the lead: the water jetting out under it leads further
// at T <= 1.19. What this test printed (dp = a/40, 2026-11-25): WCSPH leads by 12.8 to 17.9 % for
// 0.84 <= T <= 1.83 and by 7.2 to 10.1 % for 1.98 <= T <= 2.32 (PCISPH and standard SPH within 1.9 points
// of WCSPH); halving dp moves the front further ahead by up to 3 points (docs/validation.md, sweep
// dam_break_methods), so the lead is not a resolution artefact.
// Read as time, the front arrives early by an almost constant Delta T = 0.2 (docs/validation.md).
// What else we tried (WCSPH, dp = a/40, lead at T = 0.84 / 1.19 / 1.83 / 2.32, with the build of 2026-11-22;
// defaults then 13.7 / 17.8 / 12.8 / 7.2 %): free-slip walls 14.8 / 20.2 / 17.2 / 12.2 % (floor friction
// already slows the front; no-slip is the default); artificial viscosity alpha = 0: 15.0 / 20.5 / 17.6 /
// 12.4 %, alpha = 0.1: 9.8 / 13.7 / 9.3 / 3.2 %; no density diffusion 13.1 / 17.1 / 11.9 / 6.7 %; h = 2 dp
// 11.9 / 15.6 / 11.0 / 6.2 %; cubic spline 12.6 / 17.1 / 12.2 / 7.1 %. Only the artificial viscosity moves
// the front by more than 2 %, and choosing alpha to match the experiment would be a fit (it is numerical
// dissipation; water at this scale has Re ~ 1e5), as would h = 2 dp (the variants ran with the repulsive
// wall force on, which moves the front by 0.3 % at most). Independent solvers lead this experiment the same
// way: Lethe's VOF example of it (chaos-polymtl/lethe, examples/multiphysics/dam-break/dam-break-2d.py) adds
// a head start of 0.175 in T before comparing, close to the Delta T = 0.13 - 0.32 of our runs at a/40 and
// a/80 (docs/validation.md). So 10 % over 0.8 <= T < 2.3 is not a physically justified target for a
// simulation released at t = 0; the 20 % bound below stays as it was.
// The test therefore asserts, and prints every point:
//   * T = 0.41 (before the gate matters) and 2.3 <= T <= 2.5: |Z - Z_exp| <= 10 % of Z_exp,
//   * 0.8 <= T < 2.3 (gate lag): the simulation is ahead of the experiment, by at most 20 %.
// Also: no particle centre crosses a wall surface, and the dye tags survive.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_helpers.hpp"
#include "scenes.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;

namespace {

struct Point {
    double T, Z;
};

std::vector<Point> read_martin_moyce() {
    std::ifstream in(std::string(SPHFSI_FLUID_TEST_DATA) + "/martin_moyce_1952_front_n2_2.csv");
    REQUIRE(in.good());
    std::vector<Point> pts;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#' || line[0] == 'T') continue;
        std::istringstream s(line);
        Point p{};
        char comma;
        s >> p.T >> comma >> p.Z;
        pts.push_back(p);
    }
    return pts;
}

struct DamBreakResult {
    std::vector<double> errors;  // relative, per reference point with T <= 2.5
    std::uint64_t steps = 0, iterations = 0;
    double max_density_error = 0.0;
    std::size_t crossings = 0;
};

DamBreakResult run_dam_break(const Value& config, const char* name) {
    const double a = 0.1, g = 9.81, dp = config.at("dp").as_double();
    const double time_scale = std::sqrt(2.0 * g / a);
    auto solver = start(config);
    DamBreakResult res;
    std::printf("dam break (%s): T      Z_sim   Z_exp   error\n", name);
    for (const Point& p : read_martin_moyce()) {
        if (p.T > 2.5) break;
        run(*solver, p.T / time_scale, 0.01, [&](const sphfsi::protocol::AdvanceReply& r) {
            res.steps += r.substeps;
            res.iterations += r.solver_iterations;
            res.max_density_error = std::max(res.max_density_error, r.stats.at("max_density_error").as_double());
            res.crossings += solver->simulation().wall_crossings().count;
        });
        const auto& P = solver->simulation().particles();
        double x_front = 0.0;
        for (std::size_t i = 0; i < P.size(); ++i)
            if (P.kind[i] == Kind::Fluid) x_front = std::max(x_front, P.x[i][0]);
        const double Z = (x_front + 0.5 * dp) / a, err = (Z - p.Z) / p.Z;
        res.errors.push_back(err);
        std::printf("dam break (%s): %.2f   %.3f   %.2f   %+.1f %%\n", name, p.T, Z, p.Z, 100 * err);
    }
    // Dye: the two halves of the column keep their tags (0 left, 1 right), half the particles each.
    const auto& P = solver->simulation().particles();
    std::size_t left = 0, right = 0;
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid) (P.tag[i] == 0 ? left : right) += 1;
    CHECK(left == right);
    std::printf("dam break (%s): %llu steps, %llu PCISPH iterations, largest density error %.5f of rho0, "
                "%zu wall crossings\n", name, static_cast<unsigned long long>(res.steps),
                static_cast<unsigned long long>(res.iterations), res.max_density_error, res.crossings);
    return res;
}

void check_front(const DamBreakResult& res) {
    const auto pts = read_martin_moyce();
    for (std::size_t k = 0; k < res.errors.size(); ++k) {
        const double T = pts[k].T, e = res.errors[k];
        CAPTURE(T);
        CAPTURE(e);
        if (T < 0.8 || T >= 2.3)
            CHECK(std::abs(e) <= 0.10);
        else
            CHECK((e >= 0.0 && e <= 0.20));  // ahead of the gate-delayed experiment, bounded
    }
    CHECK(res.crossings == 0);
}

}  // namespace

TEST_SUITE("dam_break") {
    TEST_CASE("WCSPH surge front against Martin & Moyce (1952)") {
        const auto res = run_dam_break(wcsph(dam_break(0.1 / 40)), "WCSPH");
        check_front(res);
    }

    TEST_CASE("PCISPH surge front, and the density error stays under eta") {
        const auto res = run_dam_break(pcisph(dam_break(0.1 / 40)), "PCISPH");
        check_front(res);
        CHECK(res.iterations >= 3 * res.steps);   // at least three corrections per step
        CHECK(res.max_density_error < 0.01);      // eta = 0.01 (default)
    }

    TEST_CASE("standard SPH: compressibility at the thesis's stiffness is measured and reported") {
        // p = k (rho - rho0) with the default k = 1000 m^2/s^2 (c = 31.6 m/s), otherwise the WCSPH set-up.
        // There is no pass/fail bound on the compression itself: it is the number the thesis discusses, and
        // it is printed and recorded (docs/benchmarks.md); it must be finite and the run must stay sane.
        const auto res = run_dam_break(with(wcsph(dam_break(0.1 / 40)), {{"pressure.model", "standard"}}), "standard SPH");
        std::printf("standard SPH: largest compression (rho - rho0)/rho0 = %.4f\n", res.max_density_error);
        CHECK(std::isfinite(res.max_density_error));
        CHECK(res.max_density_error > 0.0);
        CHECK(res.crossings == 0);
        for (double e : res.errors) CHECK(std::abs(e) < 0.25);  // the front still behaves like water
    }
}
