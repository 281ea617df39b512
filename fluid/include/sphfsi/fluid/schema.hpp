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

// Validates a raw [fluid] section and returns it complete; throws ConfigError listing every problem.
sphfsi::Value validate_scene(const sphfsi::Value& fluid, const std::string& source = "scene");

}  // namespace sphfsi::fluid
