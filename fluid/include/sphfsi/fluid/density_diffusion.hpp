#pragma once
// Delta-SPH density diffusion in the continuity equation (fluid-fluid pairs only):
//   drho_i/dt += delta h c0 sum_j 2 psi_ij (x_ij . grad_i W_ij) / (r^2 + eta^2) V_j
// Molteni & Colagrossi (2009): psi_ij = rho_i - rho_j. Near a free surface under gravity this diffuses the
// hydrostatic density gradient itself, which slowly drains pressure from the bottom; Fourtakas et al. (2019)
// subtract the hydrostatic part, psi_ij = (rho_i - rho_j) - (rho_i^H - rho_j^H), with
// rho_i^H - rho_j^H = rho0 g . x_ij / c0^2 (the linearised equation of state; pairs are < 2h apart).
#include "sphfsi/fluid/settings.hpp"
#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

template <int Dim>
struct DiffusionParams {
    DensityDiffusion model = DensityDiffusion::None;
    double coef = 0.0;           // delta h c0
    Vec<Dim> hydro{};            // rho0 g / c0^2 (Fourtakas), zero otherwise
};

// Contribution to drho_i/dt divided by m_j, with F = W'(r)/r of the gradient kernel and 1/rho_j.
// The published term divides x_ij . grad W_ij by r^2 + eta^2, eta^2 = 0.01 h^2, to keep it finite for close
// pairs. Here x_ij . grad W_ij = F r^2, so the quotient is F r^2/(r^2 + eta^2): exactly F but for the guard,
// which only weakens the nearest pairs (by 2 % at r = 0.7 h) and needs a division per pair, about 17 % of the
// continuity pass's time (docs/benchmarks.md, "Profile"). Every gradient kernel here has a finite F at
// r > 0 (the spiky kernel's grows like 1/r, as does its pressure force), so the term is evaluated exactly.
template <int Dim>
inline double density_diffusion(const DiffusionParams<Dim>& p, double rho_i, double rho_j, double inv_rho_j,
                                const Vec<Dim>& dx, double F) {
    const double psi = (rho_i - rho_j) - dot(p.hydro, dx);
    return p.coef * 2.0 * psi * F * inv_rho_j;
}

}  // namespace sphfsi::fluid
