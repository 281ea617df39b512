// The pair-mean kernel gradient correction of the pressure term (pressure.kernel_correction,
// fluid/include/sphfsi/fluid/pressure_correction.hpp).
//
// 1. Stress carried by a uniform pressure. On a lattice stretched 1.25 : 0.8 and turned 30 degrees, the
//    uncorrected pair forces of a uniform pressure p carry, per particle, the stress p M with M the second
//    moment of the kernel gradient: 1.7 % of p as shear. Corrected, p I exactly (L M = I on a lattice, where
//    every L is the same). Reference: the stress of a fluid at rest, p I. Tolerance: 1e-12 (round-off).
// 2. Wind-driven flow from an uneven start. The periodic section of the wind basin (as in
//    test_channel_flows.cpp, at the basin's depth D = 0.04 m, 20 dp wide), but started from the lattice with
//    each particle moved by up to 0.3 dp in x and y, so the flow runs on an uneven arrangement like the one
//    the closed basin's circulation leaves. Reference: u(z) = tau D/(4 mu) (3 s^2 - 2 s). Tolerance: relative L2
//    error 5 % (issue 4) of the profile averaged over 2 s <= t <= 4 s in layers of dp. Measured: 1.8 %
//    corrected; 10.6 % with the same start uncorrected (the flow 7 - 9 % too slow), and within 3 % uncorrected
//    from the undisturbed lattice.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "run_helpers.hpp"
#include "scenes.hpp"
#include "wind_section.hpp"
#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/kernel_dispatch.hpp"
#include "sphfsi/fluid/kernels.hpp"
#include "sphfsi/fluid/particles.hpp"
#include "sphfsi/fluid/pressure_correction.hpp"

using namespace sphfsi::fluid;
using namespace fluid_test;

TEST_SUITE("pressure_correction") {
    TEST_CASE("a uniform pressure carries an isotropic stress on an anisotropic lattice once corrected") {
        const double a = 1.25, b = 0.8, turn = std::numbers::pi / 6, h = 1.5, rho0 = 1000.0, mass = rho0 * a * b;
        const int n = 20;
        ParticleStore<2> P;
        P.resize(static_cast<std::size_t>((2 * n) * (2 * n)));
        std::size_t k = 0;
        for (int i = -n; i < n; ++i)
            for (int j = -n; j < n; ++j, ++k) {
                const double u = i * a, w = j * b;
                P.x[k] = Vec2{{std::cos(turn) * u - std::sin(turn) * w, std::sin(turn) * u + std::cos(turn) * w}};
                P.rho[k] = rho0;
                P.kind[k] = Kind::Fluid;
                P.div_r[k] = 2.0f;  // a full support: corrected
            }
        CellGrid<2> grid;
        grid.configure(Vec2{{-40.0, -40.0}}, Vec2{{40.0, 40.0}}, 2.0 * h, {false, false});
        std::vector<std::uint32_t> order;
        grid.build(P.x, order);
        std::vector<unsigned char> scratch;
        P.reorder(order, scratch);
        const WendlandC2Kernel<2> kg(h);
        std::vector<Mat<2>> L;
        correction_matrices(P, grid, kg, mass, 1.8f, L);

        // The particle nearest the centre, far from the patch's edges, and its pairs.
        std::size_t c = 0;
        for (std::size_t q = 0; q < P.size(); ++q)
            if (norm2(P.x[q]) < norm2(P.x[c])) c = q;
        const double p = 1.0, V = mass / rho0;
        double plain[4] = {}, corrected[4] = {}, LM[4] = {};
        for (std::size_t q = 0; q < P.size(); ++q) {
            const Vec2 d = P.x[c] - P.x[q];
            const double r = std::sqrt(norm2(d));
            if (q == c || r >= 2.0 * h) continue;
            const double F = kg.grad_factor(r);
            // Per-particle stress of the pair forces, sum_j f_ij (x) x_ij / (2 V), with f_ij of the symmetric
            // term at uniform p: -2 p V^2 F x_ij uncorrected, (L_i + L_j)/2 x_ij in place of x_ij corrected.
            const Vec2 dc = pair_corrected(L[c], L[q], d);
            for (int u = 0; u < 2; ++u)
                for (int w = 0; w < 2; ++w) {
                    plain[2 * u + w] += -2.0 * p * V * V * F * d[u] * d[w] / (2.0 * V);
                    corrected[2 * u + w] += -2.0 * p * V * V * F * dc[u] * d[w] / (2.0 * V);
                }
        }
        for (int u = 0; u < 2; ++u)
            for (int w = 0; w < 2; ++w)
                for (int v = 0; v < 2; ++v) LM[2 * u + w] += L[c][static_cast<std::size_t>(2 * u + v)] * plain[2 * v + w] / p;
        std::printf("uniform p on the turned lattice: uncorrected stress [%.4f %.4f; %.4f %.4f] p, corrected [%.2e %.2e; %.2e %.2e] "
                    "- p I\n", plain[0], plain[1], plain[2], plain[3], corrected[0] - p, corrected[1], corrected[2], corrected[3] - p);
        CHECK(std::abs(plain[1]) > 0.01 * p);  // the lattice is anisotropic enough to show the defect
        for (int u = 0; u < 2; ++u)
            for (int w = 0; w < 2; ++w) {
                const double want = u == w ? p : 0.0;
                CHECK(std::abs(corrected[2 * u + w] - want) < 1e-12);
                CHECK(std::abs(LM[2 * u + w] - (u == w ? 1.0 : 0.0)) < 1e-12);
            }

        // Where the correction is off (L = I): a boundary particle; a fluid particle whose divergence of
        // position says its support is not full (below the bound, here 1.8); and one whose support is truncated though its
        // divergence was not looked at, the patch's corner, where M is about a quarter of I (det M < 1/4).
        const auto is_identity = [](const Mat<2>& m) { return m[0] == 1.0 && m[1] == 0.0 && m[2] == 0.0 && m[3] == 1.0; };
        CHECK_FALSE(is_identity(L[c]));
        std::size_t corner = 0, other = c == 0 ? 1 : 0;  // other: c's nearest neighbour, interior too
        for (std::size_t q = 0; q < P.size(); ++q) {
            if (norm2(P.x[q]) > norm2(P.x[corner])) corner = q;
            if (q != c && norm2(P.x[q] - P.x[c]) < norm2(P.x[other] - P.x[c])) other = q;
        }
        CHECK_FALSE(is_identity(L[other]));
        P.div_r[c] = 1.7f;
        P.kind[other] = Kind::Wall;
        correction_matrices(P, grid, kg, mass, 1.8f, L);
        CHECK(is_identity(L[c]));
        CHECK(is_identity(L[other]));
        CHECK(is_identity(L[corner]));
    }

    // Where a support counts as full is 0.9 Dim = 1.8, or 0.95 of a full support's divergence of position on
    // the initial lattice where that is lower (1.8 alone is above the spiky gradients' 1.773 at h = dp: with
    // "mueller" at h_over_dp = 1 no particle was corrected; a review, 2026-11-28). So lattice_divergence must
    // be what the rate pass computes
    // for a particle of the initial lattice with a full support: checked against the water's interior after
    // a first step of 1 us (the lattice moves by 5e-12 m), to 1e-5 (float storage), with summed densities,
    // which are rho0 there (hydrostatic continuity densities would scale it by rho0/rho), a support from the
    // walls (whose particles' densities come from the walls' pressures). Reference: the continuum
    // value Dim, to which every kernel's lattice sum is close (here 1.77 - 2.03). (The Gaussian at h = dp was
    // 2e-3 off: its support, 3 dp, passes through lattice points, which rounding puts inside or outside, and
    // its gradient there is not zero; h = 1.1 dp, with four wall layers, avoids that.)
    TEST_CASE("a full support's divergence of position is the rate pass's on the initial lattice") {
        const double H = 0.1, W = 0.1, dp = H / 40;
        struct Case { const char* name; KernelChoice kernel; double h_over_dp; };
        for (const auto& [name, kernel, h_over_dp] : {Case{"mueller", KernelChoice::Mueller, 1.0}, Case{"wendland", KernelChoice::Wendland, 1.5},
                                                      Case{"cubic_spline", KernelChoice::CubicSpline, 1.3},
                                                      Case{"gaussian", KernelChoice::Gaussian, 1.1}}) {
            CAPTURE(name);
            auto solver = start(with(wcsph(water_tank(dp, W, 0.12, W, H)),
                                     {{"kernel", name}, {"h_over_dp", h_over_dp}, {"pressure.kernel_correction", true},
                                      {"density.method", "summation"}, {"density.diffusion", "none"},
                                      {"tank.wall_layers", 4}}));
            run(*solver, 1e-6, 1e-6);
            const auto& sim = solver->simulation();
            const double expected = with_kernels<2>(kernel, h_over_dp * dp, [&](const auto&, const auto& kg) {
                return lattice_divergence<2>(kg, dp);
            });
            const auto& P = sim.particles();
            const double r = sim.support();
            double worst = 0.0;
            int counted = 0;
            for (std::size_t i = 0; i < P.size(); ++i) {
                const auto& x = P.x[i];
                // Its neighbours' sums full too, and no wall particle (their densities are the walls' pressures').
                if (P.kind[i] != Kind::Fluid || x[1] > H - 2 * r || x[1] < r || x[0] < r || x[0] > W - r) continue;
                worst = std::max(worst, std::abs(P.div_r[i] - expected));
                ++counted;
            }
            MESSAGE(std::string(name) << " at h = " << h_over_dp << " dp: lattice divergence " << expected
                                        << ", the rate pass's within " << worst << " over " << counted << " particles");
            CHECK(counted > 100);
            CHECK(worst < 1e-5);
            CHECK(std::abs(expected - 2.0) < 0.25);
            CHECK(full_support_divergence<2>(expected) < expected);  // the interior of the lattice is corrected
        }
    }

    TEST_CASE("wind-driven flow from a jittered lattice is within 5 % once corrected") {
        const double D = 0.04, dp = D / 20, nu = 1e-3, tau = 5.0, W = 20 * dp;
        auto s = start(with(wind_section(D, dp, W, tau, nu),
                            {{"pressure.c0", 8.86},  // the closed basin's, 10 sqrt(2 g D)
                             {"pressure.kernel_correction", true}}));
        {
            // The uneven start. The solver offers no way to move particles (a scene never needs one), so the
            // test writes the positions it has just been given; they are re-sorted at the first step.
            auto& P = const_cast<ParticleStore<2>&>(s->simulation().particles());
            std::mt19937 rng(7);
            std::uniform_real_distribution<double> jitter(-0.3 * dp, 0.3 * dp);
            for (std::size_t i = 0; i < P.size(); ++i)
                if (P.kind[i] == Kind::Fluid) {
                    P.x[i][0] += jitter(rng);
                    P.x[i][1] = std::max(0.5 * dp, P.x[i][1] + jitter(rng));
                }
        }
        run(*s, 2.0, 0.05);
        LayerProfile profile(D, dp);
        while (s->simulation().time() < 4.0 - 1e-9) {
            run(*s, s->simulation().time() + 0.05, 0.05);
            profile.add(s->simulation().particles());
        }
        REQUIRE(profile.every_layer_filled());
        const double e = profile.l2_error(tau, wind_rho0 * nu);
        std::printf("jittered wind section, corrected: relative L2 error %.2f %% over t = 2 - 4 s (tolerance 5 %%)\n", 100 * e);
        CHECK(e < 0.05);
    }
}
