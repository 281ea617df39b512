// Hydrostatic tank at rest: after settling, pressure grows linearly with depth, p = rho0 g (H - y), and
// nothing moves. Set-up: a 0.1 m x 0.1 m column of water in a tank of the same width, dp = H/40, h = 1.5 dp
// (Wendland), 1.5 s of settling, WCSPH
// (Tait, c0 = 10 sqrt(2 g H)), continuity with Fourtakas density diffusion, Adami walls, artificial
// viscosity. Reference: hydrostatics; the total weight fixes p at the bottom to rho0 g H whatever the
// compression. Tolerances from the issue: 2 % at the bottom, velocities below 1 % of sqrt(g H).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "run_helpers.hpp"
#include "scenes.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;

TEST_SUITE("hydrostatic") {
    TEST_CASE("hydrostatic tank at rest") {
        const double H = 0.1, dp = H / 40, g = 9.81, rho0 = 1000.0;
        Value f;
        f.make_table();
        f = with(f, {{"dp", dp}, {"tank.width", 0.1}, {"tank.height", 0.12}});
        f.as_table_mut()["water"] = Value(Value::Array{block(0.0, 0.0, 0.1, H)});
        auto solver = start(wcsph(f));
        std::size_t crossings = 0;
        run(*solver, 1.5, 0.05, [&](const auto&) { crossings += solver->simulation().wall_crossings().count; });
        const auto& P = solver->simulation().particles();
        // Layer-averaged pressure against depth.
        const int layers = 40;
        std::vector<double> p_sum(layers, 0.0), y_sum(layers, 0.0);
        std::vector<int> count(layers, 0);
        double v_max = 0.0;
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != Kind::Fluid) continue;
            v_max = std::max(v_max, norm(P.v[i]));
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
        std::printf("hydrostatic: largest speed %.2e m/s = %.3f %% of sqrt(g H) (tolerance 1 %%)\n", v_max,
                    100 * v_max / std::sqrt(g * H));
        CHECK(bottom_error < 0.02);
        CHECK(v_max < 0.01 * std::sqrt(g * H));
        CHECK(crossings == 0);
    }
}
