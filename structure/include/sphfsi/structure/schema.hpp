#pragma once
// The `[structure]` scene section: every key, its unit, range and default, plus the cross-key rules
// (supports and loads sit on nodes, members have length, ...). The coordinator validates scenes with it
// before starting anything; the participant re-validates what INIT hands it. Deliberately free of Eigen
// so that the coordinator can link it cheaply.
#include "sphfsi/protocol/schema.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::structure {

const schema::TableSchema& scene_schema();

// Validates a `[structure]` section and returns it with every default filled in, including those of
// optional sub-tables that the scene left out (the generic validator only fills tables that are
// present). Throws ConfigError listing every problem, each prefixed with `source`.
Value validated_config(const Value& section, const std::string& source = "structure");

}  // namespace sphfsi::structure
