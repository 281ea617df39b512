#pragma once
// Byte image of a State for CHECKPOINT / resume. Doubles are stored bit for bit, so a resumed run
// continues with identical numbers. Layout (little-endian): magic "sphfsi-structure-state-v3",
// u64 dof count, u64 element count, f64 mesh fingerprint, f64 t, u64 step, f64 external work, f64 initial
// energy, f64 energy scale, then u, v, a (dof count f64 each). Versions 1 (neither energy) and 2 (the scale
// alone) are still read; a run resumed from them goes without the energy check.
#include <cstdint>
#include <vector>

#include "sphfsi/structure/frame_dynamics.hpp"

namespace sphfsi::structure {

std::vector<std::uint8_t> encode_state(const State& state, const Model& model);
// Throws SolverError("bad_config") when the blob is not a state of this model.
State decode_state(const std::vector<std::uint8_t>& bytes, const Model& model);

}  // namespace sphfsi::structure
