#pragma once
// One-step implicit integrators for M a + D v + f_int(u) = f_ext, written in one form so that a single
// Newton loop serves all of them. The unknown is u_{n+1}; with du = u_{n+1} - u_n,
//   a_{n+1} = c0 du - c1 v_n - c2 a_n,      v_{n+1} = c3 du + c4 v_n + c5 a_n,
// and the balance is enforced at weighted points in time:
//   (1-am) M a_{n+1} + am M a_n + (1-af) [D v + f_int - f_ext]_{n+1} + af [D v + f_int - f_ext]_n = 0.
// backward Euler (first-order form: v_{n+1} = du/h, a_{n+1} = (v_{n+1} - v_n)/h, am = af = 0),
// Newmark (beta = 1/4, gamma = 1/2, am = af = 0),
// generalized-alpha (Chung & Hulbert 1993, J. Appl. Mech. 60:371: am = (2 rho - 1)/(rho + 1),
// af = rho/(rho + 1), gamma = 1/2 - am + af, beta = (1 - am + af)^2 / 4). For the nonlinear internal force
// the alpha-weighted average of forces is used (af f_int(u_n) + (1-af) f_int(u_{n+1})), which equals
// Chung & Hulbert's scheme for linear problems.
#include "sphfsi/structure/config.hpp"

namespace sphfsi::structure {

struct StepCoefficients {
    double c0 = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0, c5 = 0;
    double alpha_m = 0, alpha_f = 0;
};

struct NewmarkParameters {
    double alpha_m = 0, alpha_f = 0, beta = 0.25, gamma = 0.5;
};
NewmarkParameters generalized_alpha_parameters(double rho_inf);

StepCoefficients step_coefficients(IntegratorKind kind, double rho_inf, double h);

// Algorithmic damping ratio of backward Euler at W = omega h: its per-step amplification is
// (1 + i W)^-1, i.e. modulus (1 + W^2)^-1/2 and phase atan W, so xi = ln(1 + W^2) / (2 atan W).
double backward_euler_damping_ratio(double omega_h);

// Largest step that keeps the mode of circular frequency `omega` accurate (see TimeSpec / schema docs):
// at least steps_per_period steps per period and, for backward Euler, an algorithmic damping ratio of
// at most max_numerical_damping.
double accuracy_step(const TimeSpec& time, double omega);

}  // namespace sphfsi::structure
