#pragma once
// Wall and solid particles under the Adami, Hu & Adams (2012) boundary condition: each boundary particle w
// takes the pressure the fluid would have there, extrapolated with the kernel from its fluid neighbours f
// and corrected for the hydrostatic (and wall-acceleration) head between them:
//   p_w = ( sum_f p_f W_wf + (g - a_w) . sum_f rho_f (x_w - x_f) W_wf ) / sum_f W_wf
// and a density from the inverse equation of state. For no-slip, viscous terms see the ghost velocity
// v_w' = 2 v_w - sum_f v_f W_wf / sum_f W_wf, so the velocity interpolated at the wall surface is the wall's.
// A boundary particle with no fluid neighbour gets p = 0 (nothing pushes on it) and its own velocity.
#include <algorithm>
#include <cstdint>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

// `density_of` maps an extrapolated pressure to a density; `acceleration_of(w)` is the boundary particle's
// own acceleration (zero for fixed walls, the kinematic acceleration of a moving solid particle).
// `solids_only`: leave wall particles alone (a coupling window's new acceleration changes only the solids').
template <int Dim, class KernelW, class DensityOf, class AccelerationOf>
void extrapolate_boundary_state(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelW& kw,
                                const Vec<Dim>& gravity, bool clamp_negative, DensityOf&& density_of,
                                AccelerationOf&& acceleration_of, bool solids_only = false) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2();
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        int nr = -1;
        for (std::uint32_t w = begin; w < end; ++w) {
            if (solids_only ? P.kind[w] != Kind::Solid : !is_boundary(P.kind[w])) continue;
            if (nr < 0) nr = grid.ranges(cell, ranges);
            const V xw = P.x[w];
            double sum_w = 0.0, sum_p = 0.0;
            V sum_rho_dx{}, sum_v{};
            for (int r = 0; r < nr; ++r)
                for (std::uint32_t f = ranges[r].begin; f < ranges[r].end; ++f) {
                    if (P.kind[f] != Kind::Fluid) continue;
                    const V dx = xw - (P.x[f] + ranges[r].shift);
                    const double r2 = norm2(dx);
                    if (r2 >= R2) continue;
                    const double wk = kw.w(std::sqrt(r2));
                    sum_w += wk;
                    sum_p += P.p[f] * wk;
                    sum_rho_dx += dx * (P.rho[f] * wk);
                    sum_v += P.v[f] * wk;
                }
            if (sum_w > 0.0) {
                double p = (sum_p + dot(gravity - acceleration_of(w), sum_rho_dx)) / sum_w;
                if (clamp_negative) p = std::max(p, 0.0);
                P.p[w] = p;
                P.rho[w] = density_of(p);
                P.v_visc[w] = P.v[w] * 2.0 - sum_v * (1.0 / sum_w);
            } else {
                P.p[w] = 0.0;
                P.rho[w] = density_of(0.0);
                P.v_visc[w] = P.v[w];
            }
        }
    });
}

}  // namespace sphfsi::fluid
