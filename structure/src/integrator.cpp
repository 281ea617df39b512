#include "sphfsi/structure/integrator.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace sphfsi::structure {

NewmarkParameters generalized_alpha_parameters(double rho_inf) {
    NewmarkParameters p;
    p.alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
    p.alpha_f = rho_inf / (rho_inf + 1.0);
    p.gamma = 0.5 - p.alpha_m + p.alpha_f;
    const double s = 1.0 - p.alpha_m + p.alpha_f;
    p.beta = 0.25 * s * s;
    return p;
}

StepCoefficients step_coefficients(IntegratorKind kind, double rho_inf, double h) {
    StepCoefficients c;
    if (kind == IntegratorKind::BackwardEuler) {
        c.c0 = 1.0 / (h * h);
        c.c1 = 1.0 / h;
        c.c3 = 1.0 / h;
        return c;
    }
    NewmarkParameters p;  // average acceleration
    if (kind == IntegratorKind::GeneralizedAlpha) p = generalized_alpha_parameters(rho_inf);
    const double b = p.beta, g = p.gamma;
    c.c0 = 1.0 / (b * h * h);
    c.c1 = 1.0 / (b * h);
    c.c2 = 1.0 / (2.0 * b) - 1.0;
    c.c3 = g / (b * h);
    c.c4 = 1.0 - g / b;
    c.c5 = h * (1.0 - g / (2.0 * b));
    c.alpha_m = p.alpha_m;
    c.alpha_f = p.alpha_f;
    return c;
}

double backward_euler_damping_ratio(double w) {
    if (w <= 0) return 0.0;
    return std::log1p(w * w) / (2.0 * std::atan(w));
}

double accuracy_step(const TimeSpec& time, double omega) {
    if (!(omega > 0)) return std::numeric_limits<double>::infinity();
    double h = 2.0 * std::numbers::pi / omega / time.steps_per_period;
    if (time.integrator == IntegratorKind::BackwardEuler) {
        // xi(W) grows monotonically from 0 (~W/2); bisect for xi(W) = max_numerical_damping.
        double lo = 0.0, hi = 1.0;
        while (backward_euler_damping_ratio(hi) < time.max_numerical_damping && hi < 1e6) hi *= 2.0;
        for (int i = 0; i < 100; ++i) {
            const double mid = 0.5 * (lo + hi);
            (backward_euler_damping_ratio(mid) < time.max_numerical_damping ? lo : hi) = mid;
        }
        h = std::min(h, lo / omega);
    }
    return h;
}

}  // namespace sphfsi::structure
