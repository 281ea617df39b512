#pragma once
// Density by summation, rho_i = m sum_j W_ij (self included), optionally Shepard (CSPM) normalised:
// rho_i = m sum_j W_ij / sum_j V_j W_ij with the particle volumes V_j = m / rho~_j of the plain sums rho~ of
// the same positions (Chen et al. 1999; Randles & Libersky 1996). With volumes from the same positions the
// mass cancels: rho_i = sum_j W_ij / sum_j (W_ij / rho~_j), a kernel-weighted harmonic mean of the
// neighbours' plain sums. It cannot exceed the largest of them, so it does not remove the kernel truncation
// deficit at a free surface; it spreads it over the top rows. A flat lattice (Wendland, h = 1.5 dp, the bulk
// at rho0 = 1000): plain sums 747.8, 980.6 and 1000.0 in the top three rows, Shepard's 813.2, 917.4 and
// 989.0; beside a wall's outer layer 999.6 (a review, 2026-11-28, which found that an earlier version of
// this header claimed the deficit removed "to first order"). It smooths the sums; the plain sums keep the
// response to compression inside. (Normalising with the previous step's densities instead would make the
// density blind to compression: particles squeezed together would raise numerator and denominator alike.)
// On a uniform lattice both forms give m sum_j W_ij, so `mass` is the summation mass (Simulation2D: rho0
// over the kernel sum of the initial lattice), with which that is exactly rho0.
// Boundary particles contribute their mass to the fluid's sum in every wall model (they fill the kernel
// support below a wall); with `boundaries_too` (the dummy model) they get a density of their own as well.
#include <cstdint>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

// `volume_density`: null for the plain sum; else the plain sums rho~ used for the volumes V_j = m / rho~_j.
template <int Dim, class KernelW>
void summation_density(const ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelW& kw, double mass,
                       bool boundaries_too, const std::vector<double>* volume_density, std::vector<double>& out) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2(), w0 = kw.w(0.0);
    out.resize(P.size());
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        const int nr = grid.ranges(cell, ranges);
        for (std::uint32_t i = begin; i < end; ++i) {
            if (P.kind[i] != Kind::Fluid && !boundaries_too) {
                out[i] = P.rho[i];
                continue;
            }
            const V xi = P.x[i];
            double sum = w0, vol = volume_density ? w0 / (*volume_density)[i] : 0.0;
            for (int r = 0; r < nr; ++r)
                for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                    const double r2 = norm2(xi - (P.x[j] + ranges[r].shift));
                    if (r2 >= R2 || j == i) continue;
                    const double w = kw.w(std::sqrt(r2));
                    sum += w;
                    if (volume_density) vol += w / (*volume_density)[j];
                }
            out[i] = volume_density ? sum / vol : mass * sum;
        }
    });
}

}  // namespace sphfsi::fluid
