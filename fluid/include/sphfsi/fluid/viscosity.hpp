#pragma once
// Viscous pair terms. Each returns its contribution to particle i's acceleration divided by the neighbour
// mass m_j (the caller multiplies once), and each is antisymmetric under i <-> j so momentum is conserved
// and the force a solid particle receives is exactly the reaction of what the fluid felt.
#include "sphfsi/fluid/settings.hpp"
#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

struct ViscosityParams {
    ViscosityModel model = ViscosityModel::None;
    double alpha = 0.0;   // artificial viscosity coefficient
    double c0 = 0.0;      // reference sound speed (artificial viscosity)
    double nu = 0.0;      // kinematic viscosity (Morris, Mueller)
    double h = 0.0;
    double eta2 = 0.0;    // 0.01 h^2: keeps mu_ij finite for close pairs (Monaghan's artificial viscosity)
    double eta2_laminar = 0.0;  // 0.001 h^2 for Morris: 0.01 h^2 would weaken the nearest-neighbour terms
                                // (r = dp = h/1.5) by 2 %, a 2 % error in every viscous flow
    double laplacian_scale = 1.0;  // Mueller: 2 Dim / sum_lattice V r^2 lap W (Simulation2D's constructor)
};

// Monaghan (1992) artificial viscosity: Pi_ij = -alpha c0 mu_ij / rho_ij for approaching pairs, with
// mu_ij = h v_ij.x_ij / (r^2 + 0.01 h^2); a_i += -m_j Pi_ij grad W. Returned as the scalar that
// multiplies m_j grad_i W_ij (it adds to the pressure coefficient).
inline double artificial_viscosity_coef(const ViscosityParams& p, double vdotx, double r2, double rho_i, double rho_j) {
    if (vdotx >= 0.0) return 0.0;
    const double mu = p.h * vdotx / (r2 + p.eta2);
    return p.alpha * p.c0 * mu * 2.0 / (rho_i + rho_j);  // = -Pi_ij
}

// Morris et al. (1997): a_i += m_j (mu_i + mu_j)/(rho_i rho_j) (x_ij . grad W)/(r^2 + eta^2) v_ij with
// mu = rho nu, i.e. nu (1/rho_i + 1/rho_j) F r^2/(r^2 + eta^2) v_ij (F = W'/r). Returns the factor on v_ij.
inline double morris_viscosity_factor(const ViscosityParams& p, double F, double r2, double inv_rho_i, double inv_rho_j) {
    return p.nu * (inv_rho_i + inv_rho_j) * F * r2 / (r2 + p.eta2_laminar);
}

// Mueller et al. (2003): a_i += nu m_j (v_j - v_i) lap W_visc / rho, symmetrised with 2/(rho_i + rho_j).
// Returns the factor on v_ij (= v_i - v_j), hence the minus sign.
inline double mueller_viscosity_factor(const ViscosityParams& p, double laplacian, double rho_i, double rho_j) {
    return -2.0 * p.nu * p.laplacian_scale * laplacian / (rho_i + rho_j);
}

}  // namespace sphfsi::fluid
