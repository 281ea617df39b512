#pragma once
// The fused rate pass: one sweep over every particle's neighbours computes, for fluid particles, the
// acceleration (pressure, viscosity, wall repulsion, gravity), the density rate (continuity +
// delta-SPH) and the divergence of position (free-surface indicator); for wall particles of the dummy
// model their density rate; for solid particles the fluid force on them. Gather form: each particle sums
// over its own neighbours, so threads never write to the same particle (no atomics, no per-thread
// buffers), at the price of visiting each pair twice.
//
// Pressure term (Monaghan 1992): a_i = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij, the
// momentum-conserving symmetric form, optionally with the pair-mean kernel gradient correction
// (pressure_correction.hpp); every pair term is antisymmetric so the fluid's momentum change due to a solid
// particle is exactly minus the force we report on it.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/density_diffusion.hpp"
#include "sphfsi/fluid/kernels.hpp"
#include "sphfsi/fluid/particles.hpp"
#include "sphfsi/fluid/pressure_correction.hpp"
#include "sphfsi/fluid/viscosity.hpp"

namespace sphfsi::fluid {

template <int Dim>
struct RateParams {
    double mass = 0.0;
    ViscosityParams visc;
    bool viscous_walls = true;       // no-slip: viscous terms act between fluid and wall/solid particles
    bool continuity = false;         // integrate density: compute drho/dt
    bool wall_continuity = false;    // dummy walls integrate their density too
    DiffusionParams<Dim> diffusion;
    bool repulsive = false;          // Monaghan (1994) wall force
    double repulsive_d = 0.0, repulsive_r0 = 0.0;
    Vec<Dim> gravity{};
    const Mat<Dim>* correction = nullptr;  // per particle L (pressure_correction.hpp); null: uncorrected
};

// Per-particle factors of the pair terms, computed once per evaluation instead of once per pair: p/rho^2
// (pressure term) and 1/rho (volume per unit mass). Taking that division out of the pair loop cut this pass's
// time by 8 % (docs/benchmarks.md, "Profile"). Side by side because the loop reads both for every neighbour.
struct RateFactors {
    double pr2, inv_rho;
};

// Monaghan (1994) Lennard-Jones-like wall force, p1 = 12, p2 = 4, acting within r0: acceleration of the
// fluid particle along x_ij (pointing away from the wall particle).
template <int Dim>
inline Vec<Dim> repulsive_acceleration(double d, double r0, const Vec<Dim>& dx, double r2) {
    const double q2 = r0 * r0 / r2, q4 = q2 * q2;
    return dx * (d * (q4 * q4 * q4 - q4) / r2);
}

// The kinematic density floor's kernel sums (simulation.cpp explains the floor), taken in this pass for the
// fluid particles below `cap` = rho(p = 0): out[i] = min(cap, scale sum_j W_ij), self included, and 0 for
// every other particle. Below cap a particle's pressure is clamped to zero, so raising its density to
// out[i] after the pass changes none of the fluid pressures the pass used (only, for these rarefied
// particles, their 1/rho in the viscous and free-surface terms and their density in the Adami wall
// extrapolation's hydrostatic term); it saves a neighbour sweep of its own (8 % of a WCSPH step,
// docs/benchmarks.md, "Profile").
struct KinematicFloor {
    double cap = 0.0, scale = 0.0;
    double* out = nullptr;
};

// `only`: when given, only the particles i with only[i] != 0 are computed (the others keep their rates);
// each is computed exactly as in a full pass.
template <int Dim, class KernelW, class KernelG>
void compute_rates(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelW& kw, const KernelG& kg,
                   const ViscosityKernel<Dim>& vk, const RateFactors* factors, const RateParams<Dim>& prm,
                   const KinematicFloor* floor = nullptr, const std::uint8_t* only = nullptr) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2(), m = prm.mass;
    const bool diffusion = prm.continuity && prm.diffusion.model != DensityDiffusion::None;
    const ViscosityModel vmodel = prm.visc.model;
    const double rep_r02 = prm.repulsive_r0 * prm.repulsive_r0;
    const V* x = P.x.data();
    const V* v = P.v.data();
    const V* vv = P.v_visc.data();
    const double* rho = P.rho.data();
    const Kind* kind = P.kind.data();
    const double w0 = kw.w(0.0);

    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        const int nr = grid.ranges(cell, ranges);
        for (std::uint32_t i = begin; i < end; ++i) {
            if (only && !only[i]) continue;
            const Kind ki = kind[i];
            const V xi = x[i];
            const double rho_i = rho[i];
            if (ki == Kind::Wall) {
                // Only dummy walls with an integrated density need anything here.
                double drho = 0.0;
                if (prm.wall_continuity) {
                    for (int r = 0; r < nr; ++r)
                        for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                            if (kind[j] != Kind::Fluid) continue;
                            const V dx = xi - (x[j] + ranges[r].shift);
                            const double r2 = norm2(dx);
                            if (r2 >= R2 || r2 == 0.0) continue;
                            drho += dot(v[i] - v[j], dx) * kg.grad_factor(std::sqrt(r2));
                        }
                }
                P.drho[i] = m * drho;
                P.a[i] = V{};
                if (floor) floor->out[i] = 0.0;
                continue;
            }
            const bool is_fluid = ki == Kind::Fluid;
            const bool floor_i = floor && is_fluid && rho_i < floor->cap;
            double kernel_sum = w0;
            // A solid particle's viscous velocity is its ghost velocity, as the fluid sees it.
            const V vi_visc = is_fluid ? v[i] : vv[i];
            const V vi = v[i];
            const double pr2_i = factors[i].pr2, inv_rho_i = factors[i].inv_rho;
            V acc{}, acc_direct{};
            double drho = 0.0, drho_diff = 0.0, div_r = 0.0;
            for (int r = 0; r < nr; ++r) {
                const V shift = ranges[r].shift;
                for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                    const V dx = xi - (x[j] + shift);
                    const double r2 = norm2(dx);
                    if (r2 >= R2 || r2 == 0.0) continue;  // r2 == 0: the particle itself (or a coincident one: no direction)
                    const Kind kj = kind[j];
                    const bool fluid_j = kj == Kind::Fluid;
                    if (!is_fluid && !fluid_j) continue;  // solids only feel the fluid
                    const double rr = std::sqrt(r2);
                    const double F = kg.grad_factor(rr);
                    if (floor_i) kernel_sum += kw.w(rr);
                    const double rho_j = rho[j];
                    const RateFactors fj = factors[j];
                    // The pressure term, with the pair's mean correction when asked for (the viscous and
                    // repulsive terms are not corrected).
                    double coef = 0.0;
                    if (prm.correction)
                        acc += pair_corrected(prm.correction[i], prm.correction[j], dx) * (-(pr2_i + fj.pr2) * F);
                    else
                        coef = -(pr2_i + fj.pr2);
                    const bool viscous = (is_fluid && fluid_j) || prm.viscous_walls;  // both sides of a pair alike
                    if (vmodel != ViscosityModel::None && viscous) {
                        const V vij = vi_visc - (fluid_j ? v[j] : vv[j]);
                        if (vmodel == ViscosityModel::Artificial) {
                            coef += artificial_viscosity_coef(prm.visc, dot(vij, dx), r2, rho_i, rho_j);
                        } else if (vmodel == ViscosityModel::Morris) {
                            acc += vij * morris_viscosity_factor(prm.visc, F, r2, inv_rho_i, fj.inv_rho);
                        } else {
                            acc += vij * mueller_viscosity_factor(prm.visc, vk.laplacian(rr), rho_i, rho_j);
                        }
                    }
                    acc += dx * (coef * F);
                    div_r -= F * r2 * fj.inv_rho;  // V_j / m_j
                    if (prm.continuity) {
                        drho += dot(vi - v[j], dx) * F;
                        if (diffusion && fluid_j && is_fluid) drho_diff += density_diffusion(prm.diffusion, rho_i, rho_j, fj.inv_rho, dx, F);
                    }
                    if (prm.repulsive && (is_fluid != fluid_j) && r2 < rep_r02)
                        acc_direct += repulsive_acceleration(prm.repulsive_d, prm.repulsive_r0, dx, r2);
                }
            }
            V a = acc * m + acc_direct;
            if (is_fluid) a += prm.gravity;  // the surface stress (wind) is added after this pass: surface_stress.hpp
            P.a[i] = a;  // solids: force per unit mass of the particle (the reaction), times m gives newtons
            P.drho[i] = prm.continuity ? m * (drho + drho_diff) : 0.0;
            P.div_r[i] = static_cast<float>(m * div_r);
            if (floor) floor->out[i] = floor_i ? std::min(floor->cap, floor->scale * kernel_sum) : 0.0;
        }
    });
}

}  // namespace sphfsi::fluid
