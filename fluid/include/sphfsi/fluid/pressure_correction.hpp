#pragma once
// Kernel gradient correction of the pressure term, in a momentum-conserving pair form
// (scene key pressure.kernel_correction).
//
// Why. The symmetric pressure term puts a force m^2 (p_i/rho_i^2 + p_j/rho_j^2) |F| x_ij on every pair, so
// the stress it carries is the pressure times the particles' second moment M_i = sum_j V_j (-F) x_ij (x) x_ij
// (Bonet & Lok 1999's matrix; F = W'(r)/r). On a lattice M = I and the stress is p I, as it should be. On the
// uneven arrangement a flow leaves behind, M is a little anisotropic, and the whole pressure, not only its
// gradient, then carries a shear stress: on a lattice stretched 1.25 : 0.8 and turned 30 degrees, 1.7 % of p
// (tests/fluid/test_pressure_correction.cpp). Under 200 Pa of hydrostatic pressure that is 3 Pa, as much as
// the viscous stress of the wind-driven basin (scenarios/wind_basin.toml), and it resists the shear like an
// extra viscosity: the basin's flow was 8 - 13 % too slow, and a periodic section of it started from a
// jittered lattice 7 % too slow while the same section started from the lattice is within 3 %
// (docs/validation.md, "Wind-driven closed basin").
//
// What. Each pair's kernel gradient is corrected by the mean of the two particles' L = M^-1:
//   a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) (L_i + L_j)/2 grad_i W_ij.
// The pair term stays antisymmetric (momentum is conserved, and a solid receives exactly the reaction), and
// where L is locally uniform the carried stress is p L M = p I: isotropic on any arrangement. The usual
// correction a_i = ... L_i grad W_ij (Bonet & Lok) is not antisymmetric; applied in the momentum equation
// here it made the particles unstable (docs/validation.md, the Tried table).
//
// Where. Only where a particle's support is full: L = I for boundary particles and for fluid particles whose
// divergence of position (last evaluation) is below 0.9 Dim, or below 0.95 of a full support's on the
// initial lattice where that is lower, or whose det M is below 1/4. (The lattice's own divergence is 1.93 -
// 2.03 in 2D for most kernel and h choices, which 0.9 Dim = 1.8 leaves room below, but 1.773 for the spiky
// gradients at h = dp: with "mueller" or "spiky" at h <= 1.1 dp nothing was corrected (a review,
// 2026-11-28). The lattice's bound applies only there, so every other choice corrects as before.) Near a free surface
// the truncated support makes M singular, and there the symmetric form's truncation is what imposes p = 0 at
// the surface (Colagrossi et al. 2009), which a correction would undo.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/lattice.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

template <int Dim>
using Mat = std::array<double, Dim * Dim>;  // row-major

template <int Dim>
constexpr Mat<Dim> identity_matrix() {
    Mat<Dim> m{};
    for (int a = 0; a < Dim; ++a) m[static_cast<std::size_t>(a * Dim + a)] = 1.0;
    return m;
}

inline double determinant(const Mat<2>& m) { return m[0] * m[3] - m[1] * m[2]; }
inline double determinant(const Mat<3>& m) {
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

// Inverse by cofactors (the matrices are 2x2 or 3x3 and well conditioned where they are used).
inline Mat<2> inverse(const Mat<2>& m, double det) { return {m[3] / det, -m[1] / det, -m[2] / det, m[0] / det}; }
inline Mat<3> inverse(const Mat<3>& m, double det) {
    return {(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det, (m[1] * m[5] - m[2] * m[4]) / det,
            (m[5] * m[6] - m[3] * m[8]) / det, (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
            (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det, (m[0] * m[4] - m[1] * m[3]) / det};
}

// (L_i + L_j)/2 x: the pair's corrected direction, which multiplies F like x_ij does uncorrected.
template <int Dim>
inline Vec<Dim> pair_corrected(const Mat<Dim>& Li, const Mat<Dim>& Lj, const Vec<Dim>& x) {
    Vec<Dim> out{};
    for (int a = 0; a < Dim; ++a)
        for (int b = 0; b < Dim; ++b) {
            const auto k = static_cast<std::size_t>(a * Dim + b);
            out[a] += 0.5 * (Li[k] + Lj[k]) * x[b];
        }
    return out;
}

// The smallest det M corrected, and the smallest divergence of position corrected: 0.9 Dim, or 0.95 of a full
// support's on the initial lattice (lattice_divergence) where that is lower.
inline constexpr double min_moment_determinant = 0.25;
template <int Dim>
double full_support_divergence(double lattice) { return std::min(0.9 * Dim, 0.95 * lattice); }

// The divergence of position of a particle with a full support on the lattice of spacing dp at the
// reference density: -dp^Dim sum_j F(r_j) r_j^2, as the rate pass computes it (Dim in the continuum).
template <int Dim, class KernelG>
double lattice_divergence(const KernelG& kg, double dp) {
    double sum = 0.0;
    for_each_lattice_neighbour<Dim>(dp, kg.support(), [&](const Vec<Dim>&, double r) { sum -= kg.grad_factor(r) * r * r; });
    return sum * std::pow(dp, Dim);
}

// L_i for every particle (identity where uncorrected), from the positions and densities now in P and the
// divergence of position of the last evaluation (P.div_r), corrected where it is at least `min_divergence`.
template <int Dim, class KernelG>
void correction_matrices(const ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelG& kg, double mass,
                         float min_divergence, std::vector<Mat<Dim>>& L) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2();
    L.assign(P.size(), identity_matrix<Dim>());
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        int nr = -1;
        for (std::uint32_t i = begin; i < end; ++i) {
            if (P.kind[i] != Kind::Fluid || P.div_r[i] < min_divergence) continue;
            if (nr < 0) nr = grid.ranges(cell, ranges);
            Mat<Dim> M{};
            for (int r = 0; r < nr; ++r)
                for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                    const V d = P.x[i] - (P.x[j] + ranges[r].shift);
                    const double r2 = norm2(d);
                    if (r2 >= R2 || r2 == 0.0) continue;
                    const double w = -kg.grad_factor(std::sqrt(r2)) * mass / P.rho[j];
                    for (int a = 0; a < Dim; ++a)
                        for (int b = 0; b < Dim; ++b) M[static_cast<std::size_t>(a * Dim + b)] += w * d[a] * d[b];
                }
            const double det = determinant(M);
            if (det >= min_moment_determinant) L[i] = inverse(M, det);
        }
    });
}

}  // namespace sphfsi::fluid
