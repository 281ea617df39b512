// The lifted gate ([fluid.gate], fluid/include/sphfsi/fluid/gate.hpp): a box of solid particles on the floor
// that holds the water and rises at a prescribed speed.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "run_helpers.hpp"
#include "sphfsi/fluid/gate.hpp"
#include "scenes.hpp"

using namespace fluid_test;
using sphfsi::fluid::Kind;

namespace {

// A column 0.1 m wide and H high against the left wall, held at x = 0.1 m by a gate rising at `speed`.
Value gated_column(double dp, double H, double speed) {
    return wcsph(with(water_tank(dp, 0.4, 1.5 * H, 0.1, H), {{"gate.x0", 0.1}, {"gate.lift_speed", speed}}));
}

}  // namespace

TEST_SUITE("gate") {
    TEST_CASE("the gate moves from t = 0 on: the first step's walls carry its speed, and it stops at its travel") {
        // The step's forces are evaluated at its start, so a gate that reported rest at t = 0 would hold its
        // walls still for the whole first step of its rise.
        const sphfsi::fluid::GateLift lift{2.0, 0.2};
        double offset = -1.0, velocity = -1.0;
        lift.at(-1e-9, offset, velocity);
        CHECK((offset == 0.0 && velocity == 0.0));
        lift.at(0.0, offset, velocity);
        CHECK((offset == 0.0 && velocity == 2.0));
        lift.at(0.05, offset, velocity);
        CHECK((offset == doctest::Approx(0.1).epsilon(1e-15) && velocity == 2.0));
        lift.at(0.1, offset, velocity);
        CHECK((offset == 0.2 && velocity == 0.0));
    }

    TEST_CASE("a gate that has not risen holds the column with the hydrostatic thrust rho g H^2 / 2") {
        // Reference: the hydrostatic force on a vertical wall, rho g H^2 / 2 per metre (49.05 N/m for H = 0.1 m).
        // The gate rises at 1 nm/s: not at all within the run. Measured (2026-11-26), mean over t = 0.4 - 0.5 s:
        // 4.7 % below the thrust at dp = H/10, 2.5 % at H/20, 1.3 % at H/40: first order in dp, as if the water
        // ended dp/4 below its top, (1 - dp/(4H))^2 ~ 1 - dp/(2H) (the pressure vanishes within the last half
        // spacing of the surface). So the test asserts what that says: 3 % at H/20, the error halving from
        // H/10 to H/20 (0.40 - 0.65), and the Richardson extrapolation 2 F(H/20) - F(H/10) within 1 %.
        const double H = 0.1, rho = 1000.0, g = 9.81, thrust = 0.5 * rho * g * H * H;
        auto mean_force = [&](double dp) {
            auto s = start(gated_column(dp, H, 1e-9));
            const auto& sim = s->simulation();
            CHECK(sim.solid_count() == static_cast<std::size_t>(3 * std::lround(1.5 * H / dp)));  // 3 layers, tank high
            run(*s, 0.4, 0.05);
            double fx = 0.0;
            int windows = 0;
            run(*s, 0.5, 0.01, [&](const sphfsi::protocol::AdvanceReply&) {
                for (const auto& f : sim.mean_solid_forces()) fx += f[0];
                ++windows;
            });
            fx /= windows;
            std::printf("gate: dp = H/%.0f: horizontal force %.3f N/m (rho g H^2 / 2 = %.3f)\n", H / dp, fx, thrust);
            // Nothing has passed the gate, and the water is at rest (below 1 % of sqrt(g H), as for the tank).
            const auto& P = sim.particles();
            double x_max = 0.0;
            for (std::size_t i = 0; i < P.size(); ++i)
                if (P.kind[i] == Kind::Fluid) x_max = std::max(x_max, P.x[i][0]);
            CHECK(x_max < 0.1);
            CHECK(sim.max_speed() < 0.01 * std::sqrt(g * H));
            return fx;
        };
        const double coarse = mean_force(H / 10), fine = mean_force(H / 20);
        const double e_coarse = (thrust - coarse) / thrust, e_fine = (thrust - fine) / thrust;
        CHECK(std::abs(e_fine) < 0.03);
        CHECK(e_fine / e_coarse > 0.40);
        CHECK(e_fine / e_coarse < 0.65);
        CHECK(std::abs(2 * fine - coarse - thrust) < 0.01 * thrust);
    }

    TEST_CASE("a rising gate lets the water out underneath it only") {
        // At 1 m/s the gate's bottom edge is 10 mm up at t = 10 ms and 30 mm up at 30 ms. Water past the gate's
        // face must have gone under it: no fluid centre beyond the face above the bottom edge (the gate's
        // particles sit dp/2 inside its box, so their surface is the edge).
        const double dp = 0.0025, speed = 1.0;
        auto s = start(gated_column(dp, 0.2, speed));
        const auto& P = s->simulation().particles();
        std::size_t passed = 0;
        run(*s, 0.03, 0.0025, [&](const sphfsi::protocol::AdvanceReply&) {
            const double edge = speed * s->simulation().time();
            for (std::size_t i = 0; i < P.size(); ++i)
                if (P.kind[i] == Kind::Fluid && P.x[i][0] > 0.1) {
                    ++passed;
                    CHECK(P.x[i][1] < edge);
                }
        });
        CHECK(passed > 0);  // and some has gone
    }
}
