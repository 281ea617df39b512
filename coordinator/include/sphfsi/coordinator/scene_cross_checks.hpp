#pragma once
// Rules of a scene that join its sections (the structure inside the fluid's tank, watchpoints on the wetted
// structure, ...); run by the scene schema once every key is valid on its own.
#include <string>
#include <vector>

#include "sphfsi/protocol/schema.hpp"

namespace sphfsi::coordinator {

// `external`: the roles ([participants]) whose sections a custom program checks; their keys are unknown here.
void check_across_sections(const Value& scene, const std::vector<std::string>& external, schema::Errors& errors);

}  // namespace sphfsi::coordinator
