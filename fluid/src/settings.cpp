#include "sphfsi/fluid/settings.hpp"

#include <algorithm>
#include <cmath>

#include "sphfsi/fluid/schema.hpp"

namespace sphfsi::fluid {
namespace {

template <class E, std::size_t N>
E pick(const std::string& s, const char* const (&names)[N], const E (&values)[N]) {
    for (std::size_t i = 0; i < N; ++i)
        if (s == names[i]) return values[i];
    throw sphfsi::ConfigError("unexpected choice '" + s + "'");  // unreachable after validation
}

Box read_box(const sphfsi::Value& b) {
    return Box{b.at("x0").as_double(), b.at("y0").as_double(), b.at("width").as_double(), b.at("height").as_double()};
}

std::array<double, 2> pair(const sphfsi::Value& v) {
    const auto d = v.as_doubles();
    return {d[0], d[1]};
}

}  // namespace

double FluidSettings::water_top() const {
    double top = 0.0;
    for (const auto& w : water) top = std::max(top, w.box.y0 + w.box.height);
    return top;
}

double FluidSettings::gravity_magnitude() const { return std::hypot(gravity[0], gravity[1]); }

FluidSettings read_settings(const sphfsi::Value& raw) {
    const sphfsi::Value f = validate_scene(raw, "fluid");
    FluidSettings s;
    s.dp = f.at("dp").as_double();
    s.h_over_dp = f.at("h_over_dp").as_double();
    s.rho0 = f.at("rho0").as_double();
    s.kernel = pick(f.at("kernel").as_string(), {"mueller", "poly6", "spiky", "cubic_spline", "wendland", "gaussian"},
                    {KernelChoice::Mueller, KernelChoice::Poly6, KernelChoice::Spiky, KernelChoice::CubicSpline,
                     KernelChoice::Wendland, KernelChoice::Gaussian});
    s.gravity = pair(f.at("gravity"));
    const PeriodicAxes per = periodic_axes(f);
    s.periodic = {per.x, per.y};
    s.threads = static_cast<int>(f.at("threads").as_int());
    s.step_log = f.at("step_log").as_string();

    const auto& tank = f.at("tank");
    s.tank_width = tank.at("width").as_double();
    s.tank_height = tank.at("height").as_double();
    s.wall_layers = static_cast<int>(tank.at("wall_layers").as_int());
    s.closed_top = tank.at("closed_top").as_bool();
    s.lid_velocity = pair(tank.at("lid_velocity"));
    if (const auto* water = f.find("water"))
        for (const auto& b : water->as_array())
            s.water.push_back(WaterBlock{read_box(b), static_cast<int>(b.at("tag").as_int()),
                                         pick(b.at("split").as_string(), {"none", "vertical", "horizontal"},
                                              {DyeSplit::None, DyeSplit::Vertical, DyeSplit::Horizontal})});
    if (const auto* obstacles = f.find("obstacle"))
        for (const auto& b : obstacles->as_array()) s.obstacles.push_back(read_box(b));
    if (const auto* gate = f.find("gate")) {
        const GateBox box = gate_box(f);
        s.gate = Gate{box.x0, box.thickness, box.height, gate->at("lift_speed").as_double()};
    }

    const auto& p = f.at("pressure");
    s.pressure = pick(p.at("model").as_string(), {"standard", "wcsph", "pcisph"},
                      {PressureModel::Standard, PressureModel::Wcsph, PressureModel::Pcisph});
    s.k = p.at("k").as_double();
    s.c0 = p.at("c0").as_double();
    s.u_max = p.at("u_max").as_double();
    s.gamma = p.at("gamma").as_double();
    s.background = p.at("background").as_double();
    s.clamp_negative = p.at("clamp_negative").as_bool();
    s.kernel_correction = p.at("kernel_correction").as_bool();
    s.eta = p.at("eta").as_double();
    s.min_iterations = static_cast<int>(p.at("min_iterations").as_int());
    s.max_iterations = static_cast<int>(p.at("max_iterations").as_int());

    const auto& d = f.at("density");
    s.density = pick(d.at("method").as_string(), {"summation", "shepard", "continuity"},
                     {DensityMethod::Summation, DensityMethod::Shepard, DensityMethod::Continuity});
    s.diffusion = pick(d.at("diffusion").as_string(), {"none", "molteni", "fourtakas"},
                       {DensityDiffusion::None, DensityDiffusion::Molteni, DensityDiffusion::Fourtakas});
    s.delta = d.at("delta").as_double();
    s.reinitialise_every = static_cast<int>(d.at("reinitialise_every").as_int());

    const auto& v = f.at("viscosity");
    s.viscosity = pick(v.at("model").as_string(), {"none", "artificial", "morris", "mueller"},
                       {ViscosityModel::None, ViscosityModel::Artificial, ViscosityModel::Morris, ViscosityModel::Mueller});
    s.alpha = v.at("alpha").as_double();
    s.nu = v.at("nu").as_double();

    const auto& b = f.at("boundary");
    s.wall = pick(b.at("model").as_string(), {"dummy", "adami"}, {WallModel::Dummy, WallModel::Adami});
    s.no_slip = b.at("slip").as_string() == "no_slip";
    s.repulsive = b.at("repulsive").as_bool();
    s.repulsive_d = b.at("repulsive_d").as_double();

    const auto& fs = f.at("free_surface");
    s.surface_threshold = fs.at("threshold").as_double();
    s.wind_shear = pair(fs.at("wind_shear"));

    const auto& t = f.at("time");
    s.integrator = pick(t.at("integrator").as_string(), {"symplectic_euler", "velocity_verlet", "predictor_corrector"},
                        {Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::PredictorCorrector});
    s.cfl = t.at("cfl").as_double();
    s.force_factor = t.at("force_factor").as_double();
    s.viscous_factor = t.at("viscous_factor").as_double();
    s.dt_min = t.at("dt_min").as_double();
    s.dt_max = t.at("dt_max").as_double();

    const auto& fl = f.at("failure");
    s.min_density_ratio = fl.at("min_density_ratio").as_double();
    s.max_density_ratio = fl.at("max_density_ratio").as_double();
    s.max_mach = fl.at("max_mach").as_double();
    return s;
}

std::string to_string(PressureModel m) {
    return m == PressureModel::Standard ? "standard" : m == PressureModel::Wcsph ? "wcsph" : "pcisph";
}
std::string to_string(DensityMethod m) {
    return m == DensityMethod::Summation ? "summation" : m == DensityMethod::Shepard ? "shepard" : "continuity";
}
std::string to_string(ViscosityModel m) {
    switch (m) {
        case ViscosityModel::None: return "none";
        case ViscosityModel::Artificial: return "artificial";
        case ViscosityModel::Morris: return "morris";
        case ViscosityModel::Mueller: return "mueller";
    }
    return "?";
}
std::string to_string(WallModel m) { return m == WallModel::Dummy ? "dummy" : "adami"; }
std::string to_string(Integrator m) {
    return m == Integrator::SymplecticEuler ? "symplectic_euler"
           : m == Integrator::VelocityVerlet ? "velocity_verlet"
                                              : "predictor_corrector";
}

}  // namespace sphfsi::fluid
