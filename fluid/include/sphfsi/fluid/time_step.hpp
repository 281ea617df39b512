#pragma once
// Adaptive step: the smallest of the CFL, force and viscous limits (Monaghan 1992; Morris et al. 1997),
//   dt_cfl = lambda_v h / (c_max + |u|_max),  dt_f = lambda_F sqrt(h / |a|_max),  dt_nu = lambda_nu h^2 / nu,
// with the thesis's lambda_v = 0.4 and lambda_F = 0.25 as defaults. PCISPH has no sound speed (c_max = 0).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace sphfsi::fluid {

struct StepLimits {
    double cfl = 0.4, force = 0.25, viscous = 0.125, dt_max = 0.0;
};

struct StableStep {
    double dt = 0.0;
    const char* limited_by = "";
};

inline StableStep stable_step(const StepLimits& lim, double h, double c_max, double u_max, double a_max, double nu) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    StableStep s{inf, "nothing"};
    auto take = [&](double dt, const char* why) {
        if (dt < s.dt) s = StableStep{dt, why};
    };
    if (c_max + u_max > 0.0) take(lim.cfl * h / (c_max + u_max), "the CFL condition");
    if (a_max > 0.0) take(lim.force * std::sqrt(h / a_max), "the force condition");
    if (nu > 0.0) take(lim.viscous * h * h / nu, "the viscous condition");
    if (lim.dt_max > 0.0) take(lim.dt_max, "dt_max");
    if (!std::isfinite(s.dt)) s = StableStep{lim.dt_max > 0.0 ? lim.dt_max : 1e-3, "no motion (default step)"};
    return s;
}

}  // namespace sphfsi::fluid
