#pragma once
// The `[fluid]` scene section: every key with its type, unit, range, default and meaning, plus the
// cross-key rules (water inside the tank, options that only make sense together). The coordinator links
// this small library to validate a scene before any process starts; the participant validates again.
#include "sphfsi/protocol/schema.hpp"

namespace sphfsi::fluid {

const sphfsi::schema::TableSchema& scene_schema();

// The validated section with every optional sub-table ([fluid.pressure], [fluid.time], ...) present, filled
// with defaults when the scene left it out (the schema itself only fills keys of tables that are present).
sphfsi::Value with_defaults(const sphfsi::Value& validated_fluid);

// The [fluid.gate] box of a section that has one, its defaults resolved: thickness 0 = tank.wall_layers dp
// (a full kernel support), height 0 = the tank's height. The schema's checks and read_settings both use it,
// so the two cannot disagree about where the gate stands.
struct GateBox {
    double x0 = 0, thickness = 0, height = 0;
};
GateBox gate_box(const sphfsi::Value& fluid);

// Which axes of the tank wrap (fluid.periodic: "none", "x", "y" or "xy"), read in this one place by the
// schema's checks, the settings, the memory estimate and the coordinator's cross-checks. A section without
// the key (a foreign fluid's, unvalidated) has none.
struct PeriodicAxes {
    bool x = false, y = false;
};
PeriodicAxes periodic_axes(const sphfsi::Value& fluid);

// Validates a raw [fluid] section and returns it complete; throws ConfigError listing every problem.
sphfsi::Value validate_scene(const sphfsi::Value& fluid, const std::string& source = "scene");

}  // namespace sphfsi::fluid
