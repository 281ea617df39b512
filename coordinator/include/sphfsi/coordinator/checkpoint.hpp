#pragma once
// Everything needed to continue a run exactly: the coordinator's own state and each participant's
// opaque STATE bytes. Written atomically (temporary file + rename) so a crash never leaves half of one.
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "sphfsi/coordinator/session.hpp"

namespace sphfsi::coordinator {

struct Checkpoint {
    std::string scene_file, scene_text;
    std::vector<std::string> overrides;
    double t = 0.0;
    std::uint64_t output_index = 0;       // frames written so far (next output at t0 + index * interval)
    std::uint64_t checkpoint_index = 0;
    std::uint64_t windows = 0, steps = 0;
    double fluid_dt = 0.0, structure_dt = 0.0;  // steps the participants last asked for
    InterfaceState interface;
    std::map<std::string, std::vector<std::uint8_t>> states;  // role -> STATE bytes
    // The time loop's wall and coordinator CPU time up to the checkpoint, over every segment of the run, so
    // that a resumed run's loop_wall_s covers the windows its wall_s sums (0 in checkpoints written before).
    double loop_wall_s = 0.0, loop_cpu_s = 0.0;
};

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& c);
Checkpoint read_checkpoint(const std::filesystem::path& file);

}  // namespace sphfsi::coordinator
