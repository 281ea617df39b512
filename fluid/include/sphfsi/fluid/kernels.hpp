#pragma once
// Smoothing kernels, templated on dimension. Each kernel is built from the smoothing length h and exposes
//   support()          radius beyond which it vanishes,
//   w(r)               the kernel value,
//   grad_factor(r)     W'(r) / r, so that grad_i W_ij = grad_factor(r_ij) * (x_i - x_j) without a division
//                      by r in the hot loop (and with the r -> 0 limit handled where it is finite).
// All kernels here use the same convention: support radius = support_factor * h. Mueller et al. (2003)
// write their kernels in terms of the support radius itself; we take R = 2h for them so that one
// h_over_dp gives comparable neighbour counts across kernels.
#include <cmath>
#include <numbers>

namespace sphfsi::fluid {

namespace detail {
inline constexpr double pi = std::numbers::pi;
}

// Wendland (1995) C2 function in the form used by DualSPHysics ("quintic"): W = a (1 - q/2)^4 (2q + 1).
template <int Dim>
struct WendlandC2Kernel {
    static constexpr double support_factor = 2.0;
    double h, inv_h, alpha;
    explicit WendlandC2Kernel(double h_)
        : h(h_), inv_h(1.0 / h_),
          alpha(Dim == 2 ? 7.0 / (4.0 * detail::pi * h_ * h_) : 21.0 / (16.0 * detail::pi * h_ * h_ * h_)) {}
    double support() const { return support_factor * h; }
    double w(double r) const {
        const double q = r * inv_h;
        if (q >= 2.0) return 0.0;
        const double t = 1.0 - 0.5 * q, t2 = t * t;
        return alpha * t2 * t2 * (2.0 * q + 1.0);
    }
    // dW/dr = -5 a q (1 - q/2)^3 / h, so W'/r = -5 a (1 - q/2)^3 / h^2: smooth at r = 0.
    double grad_factor(double r) const {
        const double q = r * inv_h;
        if (q >= 2.0) return 0.0;
        const double t = 1.0 - 0.5 * q;
        return -5.0 * alpha * t * t * t * inv_h * inv_h;
    }
};

// Cubic B-spline (Monaghan & Lattanzio 1985).
template <int Dim>
struct CubicSplineKernel {
    static constexpr double support_factor = 2.0;
    double h, inv_h, sigma;
    explicit CubicSplineKernel(double h_)
        : h(h_), inv_h(1.0 / h_),
          sigma(Dim == 2 ? 10.0 / (7.0 * detail::pi * h_ * h_) : 1.0 / (detail::pi * h_ * h_ * h_)) {}
    double support() const { return support_factor * h; }
    double w(double r) const {
        const double q = r * inv_h;
        if (q >= 2.0) return 0.0;
        if (q < 1.0) return sigma * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
        const double t = 2.0 - q;
        return 0.25 * sigma * t * t * t;
    }
    double grad_factor(double r) const {
        const double q = r * inv_h;
        if (q >= 2.0) return 0.0;
        if (q < 1.0) return sigma * (-3.0 + 2.25 * q) * inv_h * inv_h;
        const double t = 2.0 - q;
        return -0.75 * sigma * t * t / (q * h * h);
    }
};

// Gaussian truncated at 3h and shifted by its value there, so it is continuous at the cut and, with the
// normalisation below, integrates to exactly 1 (the plain truncation would lose ~1e-4).
template <int Dim>
struct GaussianKernel {
    static constexpr double support_factor = 3.0;
    double h, inv_h, sigma, tail;
    explicit GaussianKernel(double h_) : h(h_), inv_h(1.0 / h_), tail(std::exp(-9.0)) {
        if constexpr (Dim == 2) {
            // int_0^3h (e^{-r^2/h^2} - e^{-9}) 2 pi r dr = pi h^2 (1 - 10 e^{-9})
            sigma = 1.0 / (detail::pi * h_ * h_ * (1.0 - 10.0 * tail));
        } else {
            // int_0^3 q^2 e^{-q^2} dq = sqrt(pi)/4 erf(3) - 3/2 e^{-9};  int_0^3 q^2 e^{-9} dq = 9 e^{-9}
            const double m = 4.0 * detail::pi * (std::sqrt(detail::pi) / 4.0 * std::erf(3.0) - 1.5 * tail - 9.0 * tail);
            sigma = 1.0 / (m * h_ * h_ * h_);
        }
    }
    double support() const { return support_factor * h; }
    double w(double r) const {
        const double q = r * inv_h;
        if (q >= 3.0) return 0.0;
        return sigma * (std::exp(-q * q) - tail);
    }
    double grad_factor(double r) const {
        const double q = r * inv_h;
        if (q >= 3.0) return 0.0;
        return -2.0 * sigma * std::exp(-q * q) * inv_h * inv_h;
    }
};

// Mueller et al. (2003) poly6: W = C (R^2 - r^2)^3. Used for densities in the thesis (its gradient
// vanishes at the centre, which is why pressure uses the spiky kernel).
template <int Dim>
struct Poly6Kernel {
    static constexpr double support_factor = 2.0;
    double radius, r2max, c;
    explicit Poly6Kernel(double h_) : radius(support_factor * h_), r2max(radius * radius) {
        const double R = radius;
        c = Dim == 2 ? 4.0 / (detail::pi * std::pow(R, 8)) : 315.0 / (64.0 * detail::pi * std::pow(R, 9));
    }
    double support() const { return radius; }
    double w(double r) const {
        const double d = r2max - r * r;
        return d > 0.0 ? c * d * d * d : 0.0;
    }
    double grad_factor(double r) const {
        const double d = r2max - r * r;
        return d > 0.0 ? -6.0 * c * d * d : 0.0;
    }
};

// Mueller et al. (2003) spiky: W = C (R - r)^3; a gradient that does not vanish at the centre, so close
// particles repel (the thesis's pressure kernel). W'/r is singular at r = 0; coincident particles have no
// direction to push along, so the caller skips r = 0 and we return 0 there.
template <int Dim>
struct SpikyKernel {
    static constexpr double support_factor = 2.0;
    double radius, c;
    explicit SpikyKernel(double h_) : radius(support_factor * h_) {
        const double R = radius;
        c = Dim == 2 ? 10.0 / (detail::pi * std::pow(R, 5)) : 15.0 / (detail::pi * std::pow(R, 6));
    }
    double support() const { return radius; }
    double w(double r) const {
        const double d = radius - r;
        return d > 0.0 ? c * d * d * d : 0.0;
    }
    double grad_factor(double r) const {
        const double d = radius - r;
        return (d > 0.0 && r > 0.0) ? -3.0 * c * d * d / r : 0.0;
    }
};

// Mueller et al. (2003) viscosity kernel: W = C (-r^3/(2R^3) + r^2/R^2 + R/(2r) - 1). Its value is
// singular at r = 0 (integrable); it exists for its Laplacian, which is positive everywhere, so the
// viscous term only ever damps relative motion. In 3D the Laplacian is 45/(pi R^6) (R - r); in 2D we
// use the same shape with the constant that makes sum_j V_j (v_j - v_i) L_ij a consistent estimate of
// the Laplacian: int r^2 L dA = 2 Dim gives C_L = 40/(pi R^5).
template <int Dim>
struct ViscosityKernel {
    static constexpr double support_factor = 2.0;
    double radius, c, c_lap;
    explicit ViscosityKernel(double h_) : radius(support_factor * h_) {
        const double R = radius;
        c = Dim == 2 ? 10.0 / (3.0 * detail::pi * R * R) : 15.0 / (2.0 * detail::pi * R * R * R);
        c_lap = Dim == 2 ? 40.0 / (detail::pi * std::pow(R, 5)) : 45.0 / (detail::pi * std::pow(R, 6));
    }
    double support() const { return radius; }
    double w(double r) const {
        if (r >= radius || r <= 0.0) return r <= 0.0 ? INFINITY : 0.0;
        const double R = radius;
        return c * (-r * r * r / (2.0 * R * R * R) + r * r / (R * R) + R / (2.0 * r) - 1.0);
    }
    double grad_factor(double r) const {
        if (r >= radius || r <= 0.0) return 0.0;
        const double R = radius;
        const double dw = c * (-1.5 * r * r / (R * R * R) + 2.0 * r / (R * R) - R / (2.0 * r * r));
        return dw / r;
    }
    double laplacian(double r) const { return r < radius ? c_lap * (radius - r) : 0.0; }
};

}  // namespace sphfsi::fluid
