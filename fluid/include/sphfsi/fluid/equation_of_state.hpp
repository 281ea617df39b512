#pragma once
// Equations of state of the two explicit pressure models. Each maps density to pressure, pressure back to
// density (the Adami wall extrapolation needs the inverse) and gives the local speed of sound (the CFL
// limit). PCISPH has no equation of state: its pressures come from the correction loop (pcisph.hpp).
#include <algorithm>
#include <cmath>

namespace sphfsi::fluid {

// Standard SPH, as in the thesis: p = k (rho - rho0) + p_b (an ideal-gas-like linear law).
class StandardEos {
public:
    StandardEos(double k, double rho0, double background) : k_(k), rho0_(rho0), pb_(background) {}
    double pressure(double rho) const { return k_ * (rho - rho0_) + pb_; }
    double density(double p) const { return rho0_ + (p - pb_) / k_; }
    double sound_speed(double) const { return std::sqrt(k_); }
    double reference_sound_speed() const { return std::sqrt(k_); }

private:
    double k_, rho0_, pb_;
};

// Weakly compressible SPH: Tait's equation p = B ((rho/rho0)^gamma - 1) + p_b with B = c0^2 rho0 / gamma,
// so that the sound speed at rest is c0 (Monaghan 1994; Batchelor 1967).
class TaitEos {
public:
    TaitEos(double c0, double rho0, double gamma, double background)
        : c0_(c0), rho0_(rho0), gamma_(gamma), b_(c0 * c0 * rho0 / gamma), pb_(background), seven_(gamma == 7.0) {}
    double pressure(double rho) const {
        const double r = rho / rho0_;
        // gamma = 7 is the usual case: three multiplications instead of pow().
        const double rg = seven_ ? [&] { const double r2 = r * r, r4 = r2 * r2; return r4 * r2 * r; }() : std::pow(r, gamma_);
        return b_ * (rg - 1.0) + pb_;
    }
    double density(double p) const {
        const double base = std::max((p - pb_) / b_ + 1.0, 0.0);
        return rho0_ * std::pow(base, 1.0 / gamma_);
    }
    // c^2 = dp/drho = c0^2 (rho/rho0)^(gamma-1)
    double sound_speed(double rho) const { return c0_ * std::pow(std::max(rho / rho0_, 0.0), 0.5 * (gamma_ - 1.0)); }
    double reference_sound_speed() const { return c0_; }
    double stiffness() const { return b_; }

private:
    double c0_, rho0_, gamma_, b_, pb_;
    bool seven_;
};

}  // namespace sphfsi::fluid
