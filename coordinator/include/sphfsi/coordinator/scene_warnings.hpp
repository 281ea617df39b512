#pragma once
// Valid scenes that are known to go wrong: each warning names the keys, what happens and where it was
// measured. `sphfsi check` prints them; `sphfsi run` logs them and runs the scene as asked.
#include <string>
#include <vector>

#include "sphfsi/coordinator/scene.hpp"

namespace sphfsi::coordinator {

std::vector<std::string> scene_warnings(const Scene& scene);

}  // namespace sphfsi::coordinator
