#pragma once
// The periodic section of the wind-driven basin that test_channel_flows.cpp and test_pressure_correction.cpp
// run: a layer D deep, W wide, periodic in x, under a surface stress tau, driven back by the set-up's
// gradient as a body force -3 tau/(2 rho0 D) along x (the value for which the net flux vanishes), and its
// time-averaged velocity profile against u(z) = tau D/(4 mu) (3 s^2 - 2 s), s = z/D.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "scenes.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace fluid_test {

inline constexpr double wind_rho0 = 1000.0;

// The [fluid] section: WCSPH, continuity densities with Fourtakas diffusion, Morris viscosity, Adami walls.
inline Value wind_section(double D, double dp, double W, double tau, double nu) {
    Value f;
    f.make_table();
    f = with(f, {{"dp", dp},
                 {"periodic", "x"},
                 {"tank.width", W},
                 {"tank.height", 1.5 * D},
                 {"pressure.model", "wcsph"},
                 {"density.method", "continuity"},
                 {"density.diffusion", "fourtakas"},
                 {"viscosity.model", "morris"},
                 {"viscosity.nu", nu},
                 {"boundary.model", "adami"},
                 {"free_surface.wind_shear", vec2(tau, 0.0)}});
    f.as_table_mut()["gravity"] = vec2(-3 * tau / (2 * wind_rho0 * D), -9.81);
    f.as_table_mut()["water"] = Value(Value::Array{block(0.0, 0.0, W, D)});
    return f;
}

// The fluid's x-velocity summed in layers one dp thick over the frames added.
struct LayerProfile {
    double D, dp;
    std::vector<double> u_sum, z_sum;
    std::vector<int> count;

    LayerProfile(double depth, double spacing) : D(depth), dp(spacing) {
        const auto layers = static_cast<std::size_t>(std::lround(D / dp));
        u_sum.assign(layers, 0.0);
        z_sum.assign(layers, 0.0);
        count.assign(layers, 0);
    }

    void add(const sphfsi::fluid::ParticleStore<2>& P) {
        const int top = static_cast<int>(count.size()) - 1;
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != sphfsi::fluid::Kind::Fluid) continue;
            const auto l = static_cast<std::size_t>(std::clamp(static_cast<int>(P.x[i][1] / dp), 0, top));
            u_sum[l] += P.v[i][0];
            z_sum[l] += P.x[i][1];
            ++count[l];
        }
    }

    bool every_layer_filled() const { return std::none_of(count.begin(), count.end(), [](int c) { return c == 0; }); }

    // Relative L2 error of the layer means against the closed-basin profile, each layer taken at its mean
    // height; `label` non-null prints every layer.
    double l2_error(double tau, double mu, const char* label = nullptr) const {
        double num = 0.0, den = 0.0;
        for (std::size_t l = 0; l < count.size(); ++l) {
            const double z = z_sum[l] / count[l], sz = z / D, u = u_sum[l] / count[l];
            const double exact = tau * D / (4 * mu) * (3 * sz * sz - 2 * sz);
            num += (u - exact) * (u - exact);
            den += exact * exact;
            if (label) std::printf("%s: z = %.4f m  u = %+.5f m/s  exact %+.5f m/s\n", label, z, u, exact);
        }
        return std::sqrt(num / den);
    }
};

}  // namespace fluid_test
