// Hydrostatic tank at rest: after settling, pressure grows linearly with depth, p = rho0 g (H - y), and
// nothing moves. Set-up: a 0.1 m x 0.1 m column of water in a tank of the same width, dp = H/40, h = 1.5 dp
// (Wendland), Adami walls, artificial viscosity. Reference: hydrostatics; the total weight fixes p at the
// bottom to rho0 g H whatever the compression. Tolerances from the issue: 2 % at the bottom, velocities
// below 1 % of sqrt(g H).
//
// "After settling" is measured, not assumed. A tank started on a square lattice settles twice: the start
// (the column finds its compression, 0 - 1.5 s), then the lattice itself. Compressed, the square lattice
// gives way in a few slow rearrangements that start at the floor's centre and travel up or along the
// floor (WCSPH: up to 2.0 % of sqrt(g H) between t = 2 and 3 s; measured 2026-11-26, docs/validation.md,
// "Tank at rest"). Once it has, the tank is still (WCSPH under 0.1 %). The velocity check therefore covers
// every window of the last second of a 4 s run, not one instant: a check at 1.5 s alone had passed in the
// quiet spell between the two.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <variant>
#include <vector>

#include "run_helpers.hpp"
#include "scenes.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;
using sphfsi::protocol::F64Array;
using sphfsi::protocol::I32Array;

namespace {

double largest_fluid_speed(const sphfsi::fluid::ParticleStore<2>& P) {
    double v = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid) v = std::max(v, norm(P.v[i]));
    return v;
}

}  // namespace

TEST_SUITE("hydrostatic") {
    TEST_CASE("hydrostatic tank at rest") {
        // WCSPH (Tait, c0 = 10 sqrt(2 g H)), continuity with Fourtakas density diffusion.
        const double H = 0.1, dp = H / 40, g = 9.81, rho0 = 1000.0, t_end = 4.0, t_still = 3.0;
        auto solver = start(wcsph(water_tank(dp, 0.1, 0.12, 0.1, H)));
        std::size_t crossings = 0;
        double v_settling = 0.0, v_still = 0.0;  // largest fluid speeds over [1.5, 3) s and [3, 4] s
        run(*solver, t_end, 0.05, [&](const auto& reply) {
            crossings += wall_crossings(reply);
            const double t = solver->simulation().time();
            if (t < 1.5 - 1e-9) return;
            double& worst = t < t_still - 1e-9 ? v_settling : v_still;
            worst = std::max(worst, largest_fluid_speed(solver->simulation().particles()));
        });
        const auto& P = solver->simulation().particles();
        // Layer-averaged pressure against depth.
        const int layers = 40;
        std::vector<double> p_sum(layers, 0.0), y_sum(layers, 0.0);
        std::vector<int> count(layers, 0);
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != Kind::Fluid) continue;
            const int l = std::clamp(static_cast<int>(P.x[i][1] / dp), 0, layers - 1);
            p_sum[l] += P.p[i];
            y_sum[l] += P.x[i][1];
            ++count[l];
        }
        std::printf("hydrostatic: layer  y [m]     p [Pa]    rho0 g (H - y) [Pa]  error (of rho0 g H)\n");
        double worst = 0.0;
        for (int l = 0; l < layers; l += 4) {
            const double y = y_sum[l] / count[l], p = p_sum[l] / count[l], exact = rho0 * g * (H - y);
            worst = std::max(worst, std::abs(p - exact) / (rho0 * g * H));
            std::printf("hydrostatic: %5d  %.5f  %9.2f  %9.2f            %+.4f\n", l, y, p, exact, (p - exact) / (rho0 * g * H));
        }
        const double y0 = y_sum[0] / count[0], p0 = p_sum[0] / count[0], exact0 = rho0 * g * (H - y0);
        const double bottom_error = std::abs(p0 - exact0) / exact0;
        std::printf("hydrostatic: bottom layer error %.3f %% (tolerance 2 %%), largest error along depth %.3f %% of rho0 g H\n",
                    100 * bottom_error, 100 * worst);
        std::printf("hydrostatic: largest speed over t = 3 - 4 s %.2e m/s = %.3f %% of sqrt(g H) (tolerance 1 %%); "
                    "over the lattice's settling, t = 1.5 - 3 s, %.3f %% (not checked)\n",
                    v_still, 100 * v_still / std::sqrt(g * H), 100 * v_settling / std::sqrt(g * H));
        CHECK(bottom_error < 0.02);
        // And along the whole depth (every 4th layer), as a fraction of the bottom's rho0 g H: the 2 %
        // (measured 1.38 %, 2026-11-27, largest at the bottom).
        CHECK(worst < 0.02);
        CHECK(v_still < 0.01 * std::sqrt(g * H));
        CHECK(crossings == 0);
    }

    // density.reinitialise_every = N replaces the integrated densities by the CSPM sums of the positions after
    // every N-th step, and only then. The tank's continuity densities start hydrostatic on the square lattice
    // (Tait: rho/rho0 = (1 + rho0 g (H - y)/B)^(1/7), B = rho0 c0^2/7); the sums of that lattice are rho0
    // (Simulation2D normalises the summation mass on it) wherever a particle is at least two kernel supports
    // from the surface and the walls (Shepard densities are exact there only). Ten steps of 10 us barely move
    // the lattice, so after step 9 the deepest of those particles must still be as heavy as Tait says (to 1 %;
    // measured to 1e-6), and after step 10 all of them at rho0 (to 1e-4; measured 1e-8).
    TEST_CASE("continuity densities are re-initialised from sums at every N-th step, not in between") {
        const double H = 0.1, W = 0.1, dp = H / 40, rho0 = 1000.0, g = 9.81;
        // Every integrator: velocity Verlet re-initialises within its step, the others after it.
        for (const std::string integrator : {"symplectic_euler", "velocity_verlet", "predictor_corrector"}) {
            CAPTURE(integrator);
            auto solver = start(with(wcsph(water_tank(dp, W, 0.12, W, H)),
                                     {{"density.reinitialise_every", 10}, {"time.integrator", integrator}}));
            const double margin = 2 * (2 * 1.5 * dp);  // two supports of the Wendland kernel (2 h, h = 1.5 dp)
            struct Deep { double lo = 1.0, hi = -1.0, y_min = 1.0; };
            auto deep = [&] {  // (rho - rho0)/rho0 over the fluid two supports inside, and the lowest such particle
                const auto& P = solver->simulation().particles();
                Deep d;
                for (std::size_t i = 0; i < P.size(); ++i) {
                    const auto x = P.x[i];
                    if (P.kind[i] != Kind::Fluid || x[0] < margin || x[0] > W - margin || x[1] < margin || x[1] > H - margin)
                        continue;
                    d.hi = std::max(d.hi, P.rho[i] / rho0 - 1.0);
                    d.lo = std::min(d.lo, P.rho[i] / rho0 - 1.0);
                    d.y_min = std::min(d.y_min, x[1]);
                }
                return d;
            };
            sphfsi::protocol::Progress progress;
            auto steps = [&](std::uint32_t n) {
                sphfsi::protocol::AdvanceRequest req;
                req.t = solver->simulation().time();
                req.dt = n * 1e-5;
                req.substeps = n;
                solver->advance(req, progress);
            };
            steps(9);
            const Deep before = deep();
            steps(1);
            const Deep after = deep();
            const double c0 = solver->simulation().c0(), B = rho0 * c0 * c0 / 7;
            const double tait = std::pow(1 + rho0 * g * (H - before.y_min) / B, 1.0 / 7) - 1;
            std::printf("reinitialise: deep water (rho - rho0)/rho0 after step 9: %.3e .. %.3e (Tait at y = %.5f m: %.3e); "
                        "after step 10: %.1e .. %.1e\n", before.lo, before.hi, before.y_min, tait, after.lo, after.hi);
            CHECK(solver->simulation().step_count() == 10);
            CHECK(std::abs(before.hi / tait - 1) < 0.01);
            CHECK(std::max(std::abs(after.lo), std::abs(after.hi)) < 1e-4);
        }
        // The option is refused where there is nothing to re-initialise.
        CHECK_THROWS_WITH_AS(start(with(pcisph(water_tank(dp, W, 0.12, W, H)), {{"density.reinitialise_every", 10}})),
                             doctest::Contains("density.reinitialise_every"), sphfsi::protocol::SolverError);
    }

    // PCISPH solves its pressures in each step, from zero (Solenthaler & Pajarola 2009): the pressure the
    // record shows is that of the last step. It was once zero in every frame (the non-pressure rates
    // evaluated after the step cleared it), and with a window-end step clipped to a sliver it was noisy,
    // as p ~ 1/dt^2 there. Same tank, PCISPH (eta = 1 %), 1 s, a frame every 10 ms: the bottom layer's
    // pressure in the recorded field, averaged over the frames of t = 0.5 - 1 s (PCISPH's pressure moves
    // from step to step by a few per cent, as densities within eta of rho0 do), against rho0 g (H - y)
    // within the 2 %.
    // Fourtakas et al. (2019) diffuse only the non-hydrostatic part of the density, psi_ij = (rho_i - rho_j)
    // - rho0 g . x_ij / c0^2, so on the hydrostatic column the continuity densities start with their diffusion
    // is close to zero, where Molteni & Colagrossi's (2009) full difference drains it. Both act where the
    // fluid's support is cut (the diffusion sums fluid pairs only): by the floor and the surface; inside, the
    // sum over a linear profile cancels. The first step of 10 us from rest changes those densities by the
    // diffusion and little else (the velocities it kicks are tiny): with delta = 0.1, Molteni's moves them by
    // up to 9e-7 rho0, Fourtakas's must move them by under 5 % of that (measured 3.1 %: the Tait law's
    // curvature, which the linearised hydrostatic part leaves, and the kicked velocities). A sign error in
    // that part makes it 197 % (seen so); no test could see one before (a review, 2026-11-28).
    TEST_CASE("Fourtakas diffusion leaves the hydrostatic column alone, Molteni's does not") {
        const double H = 0.1, W = 0.1, dp = H / 40;
        double change[2] = {};
        for (const int k : {0, 1}) {
            auto solver = start(with(wcsph(water_tank(dp, W, 0.12, W, H)),
                                     {{"density.diffusion", k == 0 ? "molteni" : "fourtakas"}, {"density.delta", 0.1}}));
            const auto& P = solver->simulation().particles();
            std::vector<double> before(P.size());
            for (std::size_t i = 0; i < P.size(); ++i) before[static_cast<std::size_t>(P.id[i])] = P.rho[i];
            sphfsi::protocol::Progress progress;
            sphfsi::protocol::AdvanceRequest req;
            req.t = 0.0;
            req.dt = 1e-5;
            req.substeps = 1;
            solver->advance(req, progress);
            for (std::size_t i = 0; i < P.size(); ++i)
                if (P.kind[i] == Kind::Fluid)
                    change[k] = std::max(change[k], std::abs(P.rho[i] - before[static_cast<std::size_t>(P.id[i])]) / 1000.0);
        }
        std::printf("diffusion on the hydrostatic column, first step: largest |drho|/rho0 %.3e (Molteni), %.3e (Fourtakas, %.2f %%)\n",
                    change[0], change[1], 100 * change[1] / change[0]);
        CHECK(change[0] > 1e-7);
        CHECK(change[1] < 0.05 * change[0]);
    }

    // Solenthaler & Pajarola's (2009) loop corrects at least min_iterations times (3, the minimum) and
    // stops at the first correction after that whose largest predicted density error is under eta. Water at
    // rest on its lattice without gravity has nothing to correct (its summed densities are rho0 exactly), so
    // every step takes exactly min_iterations corrections (dt_max makes a window more than one step); with an
    // eta no prediction can meet, a step makes max_iterations and is halved and retried, and the run stops at
    // dt_min naming it. (No test pinned the loop's count before: a review, 2026-11-28.)
    TEST_CASE("PCISPH corrects min_iterations times where nothing needs it, and not fewer") {
        const double dp = 0.0025;
        for (const int min_iterations : {3, 5}) {
            CAPTURE(min_iterations);
            auto solver = start(with(pcisph(water_tank(dp, 0.1, 0.12, 0.1, 0.05)),
                                     {{"gravity", vec2(0.0, 0.0)}, {"pressure.min_iterations", min_iterations},
                                      {"pressure.c0", 10.0}, {"time.dt_max", 1e-3}}));
            std::uint64_t steps = 0, iterations = 0;
            run(*solver, 0.02, 0.01, [&](const sphfsi::protocol::AdvanceReply& r) {
                steps += r.substeps;
                iterations += r.solver_iterations;
            });
            MESSAGE(steps << " steps, " << iterations << " corrections");
            CHECK(steps > 0);
            CHECK(iterations == steps * static_cast<std::uint64_t>(min_iterations));
        }
        // Under gravity with eta = 1e-12 no correction can stop the loop: the step halves to dt_min and the
        // run stops, saying so. (max_iterations 3 and a dt_min of 1e-5 s keep the halvings few: this is about
        // the stop, not about how long it takes.)
        auto strict = start(with(pcisph(water_tank(dp, 0.1, 0.12, 0.1, 0.05)),
                                 {{"pressure.eta", 1e-12}, {"pressure.max_iterations", 3}, {"time.dt_min", 1e-5}}));
        CHECK_THROWS_WITH_AS(run(*strict, 0.01, 0.01), doctest::Contains("PCISPH did not converge"),
                             sphfsi::protocol::SolverError);
    }

    TEST_CASE("PCISPH: the recorded pressure of a tank at rest") {
        const double H = 0.1, dp = H / 40, g = 9.81, rho0 = 1000.0;
        auto solver = start(pcisph(water_tank(dp, 0.1, 0.12, 0.1, H)));
        double ratio_sum = 0.0, ratio_min = 1e9, ratio_max = 0.0, v_max = 0.0;
        int frames = 0;
        run(*solver, 1.0, 0.01, [&](const auto&) {
            if (solver->simulation().time() < 0.5 - 1e-9) return;
            const auto f = solver->snapshot();
            const auto& x = std::get<F64Array>(f.at("position"));
            const auto& v = std::get<F64Array>(f.at("velocity"));
            const auto& p = std::get<F64Array>(f.at("pressure"));
            const auto& kind = std::get<I32Array>(f.at("kind"));
            double p_sum = 0.0, y_sum = 0.0;
            int count = 0;
            for (std::size_t i = 0; i < kind.shape[0]; ++i) {
                if (kind(i, 0) != 0) continue;
                v_max = std::max(v_max, std::hypot(v(i, 0), v(i, 1)));
                if (x(i, 1) >= dp) continue;
                p_sum += p(i, 0);
                y_sum += x(i, 1);
                ++count;
            }
            REQUIRE(count > 0);
            const double ratio = p_sum / (rho0 * g * (H * count - y_sum));
            ratio_sum += ratio;
            ratio_min = std::min(ratio_min, ratio);
            ratio_max = std::max(ratio_max, ratio);
            ++frames;
        });
        const double mean = ratio_sum / frames;
        std::printf("hydrostatic PCISPH: bottom layer p / rho0 g (H - y) over %d frames: mean %.4f (tolerance 2 %%), "
                    "range %.4f - %.4f; largest speed %.3f %% of sqrt(g H)\n",
                    frames, mean, ratio_min, ratio_max, 100 * v_max / std::sqrt(g * H));
        CHECK(frames == 51);  // t = 0.5, 0.51, ..., 1
        CHECK(std::abs(mean - 1.0) < 0.02);
    }

    // Adami walls take the extrapolated pressure of the fluid beside them, clamped at zero only where the
    // fluid's is (pressure.clamp_negative), in PCISPH's solve as in the other models: PCISPH's walls were
    // clamped whatever the scene said (a review, 2026-11-28). A closed box full of water (no free surface,
    // which unclamped PCISPH counts as a 25 % expansion and cannot run) under gravity pointing up: held by
    // its lid, the water's pressure falls towards the floor and is below zero there. Clamped, nothing pulls
    // and the bottom row stays within 0.2 dp of its place for 0.1 s (measured: WCSPH 0.09, PCISPH 0.16 dp
    // away from the floor). Unclamped, the floor pulls on it and draws it towards the wall surface, in both
    // models alike (measured: WCSPH from 0.50 to 0.07 dp above the floor, PCISPH to -0.06 dp; PCISPH with
    // its walls clamped in the solve stayed at 0.52 dp, unlike every other model). So the test: clamped,
    // both models' bottom rows stay (0.2 dp); unclamped, both come within 0.2 dp of the floor's surface.
    // This is the tension SPH walls share (docs/scenes.md, pressure.clamp_negative), not a reference value.
    TEST_CASE("PCISPH: wall pressures follow clamp_negative as WCSPH's do") {
        const double dp = 0.0025;
        for (const bool clamp : {true, false})
            for (const bool pci : {true, false}) {
                CAPTURE(clamp);
                CAPTURE(pci);
                const Value box = with(water_tank(dp, 0.1, 0.05, 0.1, 0.05), {{"tank.closed_top", true}});
                auto solver = start(with(pci ? pcisph(box) : wcsph(box),
                                         {{"gravity", vec2(0.0, 9.81)}, {"pressure.clamp_negative", clamp}}));
                run(*solver, 0.1, 0.01);
                const auto& P = solver->simulation().particles();
                double lowest = 1.0;
                for (std::size_t i = 0; i < P.size(); ++i)
                    if (P.kind[i] == Kind::Fluid) lowest = std::min(lowest, P.x[i][1]);
                MESSAGE(std::string(pci ? "PCISPH" : "WCSPH") << ", clamp_negative = " << clamp << ": lowest fluid centre "
                                                   << lowest / dp << " dp above the floor after 0.1 s (from 0.5)");
                if (clamp) CHECK(std::abs(lowest / dp - 0.5) < 0.2);
                else CHECK(lowest / dp < 0.2);
            }
    }

    // Summed densities weigh neighbours with rho0 over the initial lattice's kernel sum (Simulation2D), so
    // water resting on its initial lattice is at rho0, not at the lattice's quadrature of the kernel
    // integral (1.0051 rho0 for Wendland at h = 1.5 dp, which standard SPH at k = 1000 m^2/s^2 read as
    // 5.1 kPa). Reference: the definition of rho0. Tolerance 1e-8: after 1 us of fall the lattice has moved
    // by 5e-12 m; the unnormalised sums were off by 4e-5 (Gaussian) to 5e-3 (Wendland). Plain sums: every
    // fluid particle with a full neighbourhood of fluid and wall particles (not within a support of the
    // free surface; 5 wall layers cover even the Gaussian's 4.5 dp). Shepard's sums divide by volumes from
    // the neighbours' own plain sums, which are truncated within a support of the surface and of the
    // walls' outer layer, so they are rho0 only two supports inside both: checked there.
    TEST_CASE("summed densities of water on its initial lattice are rho0") {
        const double H = 0.1, W = 0.1, dp = H / 40;
        for (const char* kernel : {"wendland", "cubic_spline", "gaussian", "mueller"})
            for (const char* method : {"summation", "shepard"}) {
                CAPTURE(kernel);
                CAPTURE(method);
                auto solver = start(with(water_tank(dp, W, 0.12, W, H),
                                         {{"kernel", kernel}, {"density.method", method}, {"pressure.model", "standard"},
                                          {"tank.wall_layers", 5}, {"density.diffusion", "none"}, {"boundary.model", "adami"}}));
                run(*solver, 1e-6, 1e-6);
                const auto& P = solver->simulation().particles();
                const double r = solver->simulation().support(), inset = std::string(method) == "shepard" ? 2 * r : 0.0;
                double worst = 0.0;
                int counted = 0;
                for (std::size_t i = 0; i < P.size(); ++i) {
                    const auto& x = P.x[i];
                    if (P.kind[i] != Kind::Fluid || x[1] > H - r - inset || x[1] < inset || x[0] < inset || x[0] > W - inset)
                        continue;
                    worst = std::max(worst, std::abs(P.rho[i] / 1000.0 - 1.0));
                    ++counted;
                }
                MESSAGE(std::string(kernel) << ", " << std::string(method) << ": largest |rho/rho0 - 1| = " << worst << " over " << counted << " particles");
                CHECK(counted > 100);
                CHECK(worst < 1e-8);
            }
    }
}
