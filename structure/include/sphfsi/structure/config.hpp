#pragma once
// Plain typed view of a validated `[structure]` section (see schema.hpp for the meaning of each key).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sphfsi/protocol/value.hpp"

namespace sphfsi::structure {

using Point2 = std::array<double, 2>;

enum class Formulation { Linear, Corotational };
enum class MassKind { Consistent, Lumped };
enum class SupportType { Clamped, Pinned, Roller, Free };
enum class DampingKind { None, Simple, Rayleigh };
enum class IntegratorKind { BackwardEuler, Newmark, GeneralizedAlpha };

// Time factor of a prescribed load.
struct History {
    enum class Kind { Constant, Ramp, Sine } kind = Kind::Constant;
    double ramp_time = 1.0, frequency = 1.0, phase = 0.0, start_time = 0.0;
    std::optional<double> end_time;
    // The load switches on at start_time and off at end_time: at those instants a step that ends there takes
    // the value from its left (`Side::Left`), a step that starts there the value from its right.
    enum class Side { Left, Right };
    double factor(double t, Side side = Side::Right) const;
    // The factor's exact mean over [t0, t1] (t1 > t0): its integral, switches included, over the length.
    double mean_factor(double t0, double t1) const;
};

struct Material {
    double E = 0, nu = 0.3, rho = 0;
};
struct Section {
    double thickness = 0, depth = 1.0;
    bool plane_strain = false;
};
struct MemberSpec {
    std::string name;
    Point2 start{}, end{};
    int n_elements = 10;
    bool wetted = true;
    double pad_left = 0.0, pad_right = 0.0;  // published cross-section beyond the faces [m]
};
struct SupportSpec {
    Point2 at{};
    SupportType type = SupportType::Free;
    Point2 normal{0.0, 1.0};
};
struct PointLoadSpec {
    Point2 at{}, force{};
    double moment = 0;
    History history;
};
struct DistributedLoadSpec {
    int member = 0;
    Point2 q{};
    History history;
};
struct DampingSpec {
    DampingKind kind = DampingKind::None;
    double c = 0;
    Point2 ratios{0.02, 0.02};
    std::optional<Point2> frequencies;  // Hz
};
struct TimeSpec {
    IntegratorKind integrator = IntegratorKind::GeneralizedAlpha;
    double rho_inf = 0.9, dt_max = 1e-3;
    int resolved_modes = 3;
    double steps_per_period = 20, max_numerical_damping = 0.05;
};
struct NewtonSpec {
    double tolerance = 1e-8;
    int max_iterations = 25, load_steps = 10;
};
struct FailureSpec {
    double max_energy_created = 0.1;  // fraction of the energy scale (FrameDynamics::check_energy); 0 = off
};
struct InitialSpec {
    bool static_equilibrium = false;
    int mode = 0;
    double mode_amplitude = 0;
    std::vector<PointLoadSpec> preload;
};

struct StructureConfig {
    Formulation formulation = Formulation::Linear;
    MassKind mass = MassKind::Consistent;
    bool gravity = false;
    Point2 gravity_vector{0.0, -9.81};
    Material material;
    Section section;
    std::vector<MemberSpec> members;
    std::vector<SupportSpec> supports;
    std::vector<PointLoadSpec> point_loads;
    std::vector<DistributedLoadSpec> distributed_loads;
    DampingSpec damping;
    TimeSpec time;
    NewtonSpec newton;
    FailureSpec failure;
    InitialSpec initial;

    // Validates `section` against scene_schema() (throws ConfigError) and reads it.
    static StructureConfig from_value(const Value& section);
};

}  // namespace sphfsi::structure
