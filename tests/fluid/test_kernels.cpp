// Kernels: normalisation (integral of W is 1) and first-order consistency (the SPH gradient of a linear
// field is exact in the interior), for every kernel. Both are lattice sums: their only error is the
// quadrature error of the lattice, tiny for a kernel smooth at its centre (h/dp = 4 suffices for 1e-3),
// O(dp^2) for spiky's cusp at r = 0 (h/dp = 12) and O(dp) for the viscosity kernel's 1/r singularity
// (a finer, shifted lattice). The coarse h/dp = 1.3 sums are printed for information only.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "sphfsi/fluid/kernels.hpp"
#include "sphfsi/fluid/vec.hpp"

using namespace sphfsi::fluid;

namespace {

// sum_j W(|x_j|) dp^Dim over a square lattice through the origin (offset = 0) or shifted by half a spacing.
template <int Dim, class K>
double lattice_integral(const K& k, double dp, double offset) {
    const int n = static_cast<int>(std::ceil(k.support() / dp)) + 2;
    double sum = 0.0;
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int l = (Dim == 3 ? -n : 0); l <= (Dim == 3 ? n : 0); ++l) {
                Vec<Dim> x{};
                x[0] = (i + offset) * dp;
                x[1] = (j + offset) * dp;
                if constexpr (Dim == 3) x[2] = (l + offset) * dp;
                sum += k.w(norm(x));
            }
    return sum * std::pow(dp, Dim);
}

// sum_j V_j (f_j - f_0) grad_0 W_0j at the origin for f = a . x; the exact gradient is a.
template <int Dim, class K>
Vec<Dim> lattice_gradient(const K& k, double dp, Vec<Dim> a) {
    const int n = static_cast<int>(std::ceil(k.support() / dp)) + 2;
    Vec<Dim> g{};
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int l = (Dim == 3 ? -n : 0); l <= (Dim == 3 ? n : 0); ++l) {
                if (i == 0 && j == 0 && l == 0) continue;
                Vec<Dim> xj{};
                xj[0] = i * dp;
                xj[1] = j * dp;
                if constexpr (Dim == 3) xj[2] = l * dp;
                const Vec<Dim> dx = Vec<Dim>{} - xj;  // x_0 - x_j
                g += dx * (k.grad_factor(norm(dx)) * dot(a, xj) * std::pow(dp, Dim));
            }
    return g;
}

template <class K2, class K3>
void check_kernel(const char* name, double h_over_dp = 4.0) {
    CAPTURE(name);
    const double h = 0.01;
    const K2 k2(h);
    const double i2 = lattice_integral<2>(k2, h / h_over_dp, 0.0);
    const double i2_coarse = lattice_integral<2>(k2, h / 1.3, 0.0);
    const double i3 = lattice_integral<3>(K3(h), h / h_over_dp, 0.0);
    std::printf("kernel %-13s 2D integral %.6f (h/dp = %g), %.6f (h/dp = 1.3); 3D integral %.6f\n", name, i2, h_over_dp, i2_coarse, i3);
    CHECK(std::abs(i2 - 1.0) < 1e-3);
    CHECK(std::abs(i3 - 1.0) < 1e-3);
    const Vec2 a{{0.7, -1.3}};
    const double err = norm(lattice_gradient<2>(k2, h / h_over_dp, a) - a) / norm(a);
    // 3D too (only its normalisation was tested: a review, 2026-11-28), at the same h / dp.
    const Vec<3> a3{{0.7, -1.3, 0.4}};
    const double err3 = norm(lattice_gradient<3>(K3(h), h / h_over_dp, a3) - a3) / norm(a3);
    std::printf("kernel %-13s gradient of a linear field: relative error %.2e (2D), %.2e (3D)\n", name, err, err3);
    CHECK(err < 1e-3);
    CHECK(err3 < 1e-3);
}

}  // namespace

TEST_SUITE("kernels") {
    TEST_CASE("Wendland quintic C2") { check_kernel<WendlandC2Kernel<2>, WendlandC2Kernel<3>>("wendland"); }
    TEST_CASE("cubic B-spline") { check_kernel<CubicSplineKernel<2>, CubicSplineKernel<3>>("cubic_spline"); }
    TEST_CASE("truncated Gaussian") { check_kernel<GaussianKernel<2>, GaussianKernel<3>>("gaussian"); }
    TEST_CASE("Mueller poly6") { check_kernel<Poly6Kernel<2>, Poly6Kernel<3>>("poly6"); }
    TEST_CASE("Mueller spiky") { check_kernel<SpikyKernel<2>, SpikyKernel<3>>("spiky", 12.0); }

    TEST_CASE("Mueller viscosity kernel") {
        // Its value is singular (integrably, ~1/r) at the centre, so the lattice is shifted half a spacing off
        // the origin and refined: the quadrature error of the 1/r cusp falls like dp/R.
        const double h = 0.01;
        const ViscosityKernel<2> k2(h);
        const ViscosityKernel<3> k3(h);
        const double i2 = lattice_integral<2>(k2, k2.support() / 1500.0, 0.5);
        const double i3 = lattice_integral<3>(k3, k3.support() / 100.0, 0.5);
        std::printf("kernel viscosity     2D integral %.6f, 3D integral %.6f (shifted lattices)\n", i2, i3);
        CHECK(std::abs(i2 - 1.0) < 1e-3);
        CHECK(std::abs(i3 - 1.0) < 1e-3);
        // Gradient: the singular W' ~ 1/r^2 makes the lattice sum converge like dp; dp = R/1500.
        const Vec2 a{{0.7, -1.3}};
        const double err = norm(lattice_gradient<2>(k2, k2.support() / 1500.0, a) - a) / norm(a);
        std::printf("kernel viscosity     gradient of a linear field: relative error %.2e\n", err);
        CHECK(err < 1e-3);
        // Its Laplacian (what the thesis uses it for): sum_j V_j (f_j - f_0) L_0j = lap f for f = |x|^2 (lap = 4).
        const double dp = k2.support() / 50.0;
        double lap = 0.0;
        for (int i = -60; i <= 60; ++i)
            for (int j = -60; j <= 60; ++j) {
                const double r = std::hypot(i * dp, j * dp);
                lap += (r * r) * k2.laplacian(r) * dp * dp;
            }
        // And in 3D (lap |x|^2 = 6), untested until a review of 2026-11-28: the same lattice, a third axis.
        double lap3 = 0.0;
        for (int i = -52; i <= 52; ++i)
            for (int j = -52; j <= 52; ++j)
                for (int l = -52; l <= 52; ++l) {
                    const double r = std::sqrt(double(i * i + j * j + l * l)) * dp;
                    lap3 += (r * r) * k3.laplacian(r) * dp * dp * dp;
                }
        std::printf("kernel viscosity     Laplacian of |x|^2: %.5f (exact 4), 3D %.5f (exact 6)\n", lap, lap3);
        CHECK(std::abs(lap - 4.0) < 4e-3);
        CHECK(std::abs(lap3 - 6.0) < 6e-3);
    }
}
