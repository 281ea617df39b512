#pragma once
// The [fluid] section read into plain typed values (after validation), so the solver never looks keys up
// at run time. See schema.cpp for the meaning, units and defaults of each.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sphfsi/fluid/kernel_names.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::fluid {

enum class PressureModel { Standard, Wcsph, Pcisph };
enum class DensityMethod { Summation, Shepard, Continuity };
enum class DensityDiffusion { None, Molteni, Fourtakas };
enum class ViscosityModel { None, Artificial, Morris, Mueller };
enum class WallModel { Dummy, Adami };
enum class Integrator { SymplecticEuler, VelocityVerlet, PredictorCorrector };
enum class DyeSplit { None, Vertical, Horizontal };

struct Box {
    double x0 = 0, y0 = 0, width = 0, height = 0;
};

// A gate lifted from t = 0 (gate.hpp); thickness and height resolved from their scene defaults.
struct Gate {
    double x0 = 0, thickness = 0, height = 0, lift_speed = 0;
};

struct WaterBlock {
    Box box;
    int tag = 0;
    DyeSplit split = DyeSplit::None;
};

struct FluidSettings {
    double dp = 0.0, h_over_dp = 1.5, rho0 = 1000.0;
    KernelChoice kernel = KernelChoice::Wendland;
    std::array<double, 2> gravity{0.0, -9.81};
    std::array<bool, 2> periodic{false, false};
    int threads = 0;
    std::string step_log;

    double tank_width = 0, tank_height = 0;
    int wall_layers = 3;
    bool closed_top = false;
    std::array<double, 2> lid_velocity{0.0, 0.0};
    std::vector<WaterBlock> water;
    std::vector<Box> obstacles;
    std::optional<Gate> gate;

    PressureModel pressure = PressureModel::Wcsph;
    double k = 1000.0, c0 = 0.0, u_max = 0.0, gamma = 7.0, background = 0.0;
    bool clamp_negative = true;
    bool kernel_correction = false;  // pressure_correction.hpp
    double eta = 0.01;
    int min_iterations = 3, max_iterations = 50;

    DensityMethod density = DensityMethod::Continuity;
    DensityDiffusion diffusion = DensityDiffusion::None;
    double delta = 0.1;
    int reinitialise_every = 0;  // continuity: densities replaced by CSPM sums every N steps (0: never)

    ViscosityModel viscosity = ViscosityModel::Artificial;
    double alpha = 0.01, nu = 1e-6;

    WallModel wall = WallModel::Adami;
    bool no_slip = true;
    bool repulsive = false;
    double repulsive_d = 0.0;

    double surface_threshold = 1.5;
    std::array<double, 2> wind_shear{0.0, 0.0};

    Integrator integrator = Integrator::SymplecticEuler;
    double cfl = 0.4, force_factor = 0.25, viscous_factor = 0.125, dt_min = 1e-8, dt_max = 0.0;

    double min_density_ratio = 0.01, max_density_ratio = 1.5;
    double max_mach = 1.0;  // largest |v| / c0 of a fluid particle (c0: Simulation2D::c0)

    double h() const { return h_over_dp * dp; }
    // Highest water top: the H of sqrt(2 g H) estimates.
    double water_top() const;
    double gravity_magnitude() const;
};

// Validates (throws ConfigError naming every problem) and reads a [fluid] section.
FluidSettings read_settings(const sphfsi::Value& fluid_section);

// Name of an enum value as the scene writes it (for InitReply.info and messages).
std::string to_string(PressureModel m);
std::string to_string(DensityMethod m);
std::string to_string(ViscosityModel m);
std::string to_string(WallModel m);
std::string to_string(Integrator m);

}  // namespace sphfsi::fluid
