#pragma once
// Density rate from the continuity equation, drho_i/dt = sum_j m_j (v_i - v_j) . grad_i W_ij, plus the
// optional delta-SPH diffusion (fluid-fluid pairs), for fluid particles and, in the dummy wall model,
// for boundary particles (which see only fluid neighbours).
//
// Why its own pass: in a time step the density must be advanced with the *new* velocities, like the
// positions. Advancing density and velocity from the same old state (explicit Euler on the acoustic pair
// rho <-> v) amplifies every sound wave by sqrt(1 + (omega dt)^2) per step and the fluid rings itself to
// pieces within a few hundred steps; with rho treated as a position-like variable (updated after the
// velocity kick, from the kicked velocities) the scheme is symplectic and stable up to the CFL limit.
//
// `inv_rho`: 1/rho of every particle, computed once per pass by the caller rather than once per pair.
#include <cmath>
#include <cstdint>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/density_diffusion.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

template <int Dim, class KernelG>
void continuity_rates(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelG& kg, double mass,
                      bool boundaries_too, const DiffusionParams<Dim>& diffusion, const double* inv_rho) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2();
    const bool diffuse = diffusion.model != DensityDiffusion::None;
    const DiffusionParams<Dim> diff_params = diffusion;  // a local copy: the compiler may keep it in registers
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        const int nr = grid.ranges(cell, ranges);
        for (std::uint32_t i = begin; i < end; ++i) {
            const bool fluid = P.kind[i] == Kind::Fluid;
            if (!fluid && !boundaries_too) {
                P.drho[i] = 0.0;
                continue;
            }
            const V xi = P.x[i], vi = P.v[i];
            const double rho_i = P.rho[i];
            double drho = 0.0, diff = 0.0;
            for (int r = 0; r < nr; ++r)
                for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                    const bool fluid_j = P.kind[j] == Kind::Fluid;
                    if (!fluid && !fluid_j) continue;
                    const V dx = xi - (P.x[j] + ranges[r].shift);
                    const double r2 = norm2(dx);
                    if (r2 >= R2 || r2 == 0.0) continue;
                    const double F = kg.grad_factor(std::sqrt(r2));
                    drho += dot(vi - P.v[j], dx) * F;
                    if (diffuse && fluid && fluid_j)
                        diff += density_diffusion(diff_params, rho_i, P.rho[j], inv_rho[j], dx, F);
                }
            P.drho[i] = mass * (drho + diff);
        }
    });
}

}  // namespace sphfsi::fluid
