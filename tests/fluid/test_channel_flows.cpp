// Viscous flows between plates, periodic in x, against their analytical solutions.
//
// Poiseuille and Couette: the set-up of Morris, Fox & Zhu (1997), section 4: plates L = 1 mm apart,
// nu = 1e-6 m^2/s, rho0 = 1000 kg/m^3; Poiseuille driven by a body force F = 2e-4 m/s^2 (u_max = F L^2/(8 nu)
// = 2.5e-5 m/s), Couette by the upper plate moving at V0 = 2.5e-5 m/s; both start from rest and are compared
// with the series solutions (Morris eqs. 22 and 23). Morris laminar viscosity, Adami no-slip walls, WCSPH
// with c0 = 0.05 m/s (2000 u_max, so the step is set by the viscous limit as in Morris), dp = L/20.
// Tolerance: relative L2 error 2 % (issue 4), at each of Morris's comparison times.
//
// Wind: steady flow in a basin of depth D under a surface shear stress tau. The closed-basin profile
// u(z) = tau D/(4 mu) (3 s^2 - 2 s), s = z/D, has zero net flux: the wind piles water up at the lee shore and
// the resulting surface slope drives a return current along the bottom. We model the basin's middle
// section, periodic in x, with that slope's pressure gradient as a uniform body force -3 tau/(2 rho0 D) along
// x (the value for which the flux vanishes), plus gravity. D = 0.02 m, nu = 1e-3 m^2/s, tau = 5 Pa
// (surface speed tau D/(4 mu) = 25 mm/s, Re = 0.5), dp = D/20. The slowest transient decays as
// exp(-(pi/2)^2 nu t / D^2) (gone after 1 s); what remains is WCSPH's particle noise (the lattice relaxing
// under 200 Pa of hydrostatic pressure, ~1 mm/s, see the hydrostatic test), so the profile is averaged over
// 2 s <= t <= 4 s in layers of one dp. The flow must stand well above that noise: with tau = 1 Pa (5 mm/s)
// the noise mixes momentum and the error is 13 %; with tau = 5 Pa it is 2.6 % (1.7 % at dp = D/30).
// Tolerance: relative L2 error 5 % (issue 4).
// The whole closed basin, end walls and all (scenarios/wind_basin.toml, sweeps/wind_basin.toml), did worse
// with the plain pressure term: its circulation stirs the particles out of their lattice, and on an uneven
// arrangement the pressure term carries part of the shear stress, so the profile was 8 % off at D/20 over
// t = 3 - 5 s and 14 - 15 % once steady. The scene now corrects the pressure term's kernel gradient
// (test_pressure_correction.cpp, docs/validation.md).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <utility>

#include "run_helpers.hpp"
#include "scenes.hpp"
#include "wind_section.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;

namespace {

constexpr double pi = std::numbers::pi;

Value channel(double L, double dp, double width) {
    return with(water_tank(dp, width, L, width, L), {{"periodic", "x"},
                                                     {"tank.closed_top", true},
                                                     {"pressure.model", "wcsph"},
                                                     {"pressure.c0", 0.05},
                                                     {"pressure.clamp_negative", false},
                                                     {"density.method", "continuity"},
                                                     {"viscosity.model", "morris"},
                                                     {"viscosity.nu", 1e-6},
                                                     {"boundary.model", "adami"}});
}

// Relative L2 error of the fluid's x-velocity against u(y).
double l2_error(const sphfsi::fluid::SphSolver& s, const std::function<double(double)>& exact) {
    auto& solver = const_cast<sphfsi::fluid::SphSolver&>(s);
    const auto& P = solver.simulation().particles();
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        const double ue = exact(P.x[i][1]);
        num += (P.v[i][0] - ue) * (P.v[i][0] - ue);
        den += ue * ue;
    }
    return std::sqrt(num / den);
}

void check_against(sphfsi::fluid::SphSolver& s, const char* name, const std::vector<double>& times,
                   const std::function<double(double, double)>& exact, double tolerance) {
    std::size_t crossings = 0;
    for (double t : times) {
        run(s, t, 0.01, [&](const auto& reply) { crossings += wall_crossings(reply); });
        const double e = l2_error(s, [&](double y) { return exact(y, t); });
        std::printf("%s: t = %.4f s, relative L2 error %.3f %% (tolerance %.0f %%)\n", name, t, 100 * e, 100 * tolerance);
        CAPTURE(t);
        CHECK(e < tolerance);
    }
    CHECK(crossings == 0);
}

}  // namespace

TEST_SUITE("channel_flows") {
    TEST_CASE("Poiseuille flow (Morris et al. 1997)") {
        // Morris's laminar viscosity at L/20, and the thesis's Laplacian of Mueller's viscosity kernel at
        // L/40: its estimate sum_j V_j (v_j - v_i) lap W_ij needs twice the resolution for the same 2 %
        // (measured 2026-11-27: 1.7 - 2.6 % at L/20 and 0.6 - 1.0 % at L/40, where Morris's gives 0.8 - 1.3 %
        // and 0.3 - 0.5 %; before its constant was normalised on the lattice, 7.0 % at L/20).
        for (const auto& [model, n] : {std::pair{"morris", 20.0}, std::pair{"mueller", 40.0}}) {
        CAPTURE(model);
        const double L = 1e-3, nu = 1e-6, F = 2e-4;
        Value f = with(channel(L, L / n, L / 2), {{"viscosity.model", model}});
        f.as_table_mut()["gravity"] = vec2(F, 0.0);
        auto s = start(f);
        auto exact = [&](double y, double t) {
            double u = F / (2 * nu) * y * (L - y);
            for (int n = 0; n < 50; ++n) {
                const double k = 2 * n + 1;
                u -= 4 * F * L * L / (nu * pi * pi * pi * k * k * k) * std::sin(k * pi * y / L) * std::exp(-k * k * pi * pi * nu * t / (L * L));
            }
            return u;
        };
        check_against(*s, model, {0.0225, 0.045, 0.1125, 0.225, 1.0}, exact, 0.02);
        }
    }

    TEST_CASE("Couette flow (Morris et al. 1997)") {
        const double L = 1e-3, nu = 1e-6, V0 = 2.5e-5;
        Value f = channel(L, L / 20, L / 2);
        f.as_table_mut()["gravity"] = vec2(0.0, 0.0);
        f = with(f, {{"tank.lid_velocity", vec2(V0, 0.0)}});
        auto s = start(f);
        auto exact = [&](double y, double t) {
            double u = V0 * y / L;
            for (int n = 1; n < 200; ++n)
                u += 2 * V0 / (n * pi) * (n % 2 ? -1.0 : 1.0) * std::sin(n * pi * y / L) * std::exp(-n * n * pi * pi * nu * t / (L * L));
            return u;
        };
        check_against(*s, "Couette", {0.0225, 0.045, 0.1125, 0.225, 1.0}, exact, 0.02);
    }

}

TEST_SUITE("wind") {
    TEST_CASE("wind-driven flow in a closed basin") {
        const double D = 0.02, dp = D / 20, nu = 1e-3, tau = 5.0, W = 10 * dp;
        auto s = start(wind_section(D, dp, W, tau, nu));
        LayerProfile profile(D, dp);
        std::size_t crossings = 0;
        run(*s, 2.0, 0.05, [&](const auto& reply) { crossings += wall_crossings(reply); });
        while (s->simulation().time() < 4.0 - 1e-9) {
            run(*s, s->simulation().time() + 0.05, 0.05, [&](const auto& reply) { crossings += wall_crossings(reply); });
            profile.add(s->simulation().particles());
        }
        const double e = profile.l2_error(tau, wind_rho0 * nu, "wind");
        std::printf("wind: relative L2 error of the time-averaged profile %.2f %% (tolerance 5 %%)\n", 100 * e);
        CHECK(e < 0.05);
        CHECK(crossings == 0);
        // Detection: the outermost layer, and only it, is flagged (10 particles across the 10-dp section). The
        // total stress force is tau W whatever is flagged (each particle's share is measured on the lattice;
        // test_surface_stress.cpp checks that), so this checks the detection alone.
        const auto surface = s->simulation().free_surface_count();
        std::printf("wind: %zu free-surface particles over a %.0f-particle-wide surface\n", surface, W / dp);
        CHECK(surface == 10);
    }
}
