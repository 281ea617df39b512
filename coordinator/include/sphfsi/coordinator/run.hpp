#pragma once
// `sphfsi run`: start what the scene needs, drive the coupling, record everything, shut down cleanly.
#include <filesystem>
#include <string>
#include <vector>

namespace sphfsi::coordinator {

struct RunOptions {
    std::filesystem::path scene;           // ignored with resume
    std::vector<std::string> overrides;    // --set key=value
    std::filesystem::path out_dir;         // record.h5, record.xdmf, watchpoints.csv, run.log, checkpoint
    std::string listen;                    // non-empty: bind here and wait for remote participants
    bool resume = false;                   // continue from out_dir/checkpoint.bin
    bool overwrite = false;                // a fresh run may replace the record an earlier run left in out_dir
    bool quiet = false;                    // no progress line
};

// Returns the process exit status: 0 completed, 1 failed (participant or numerics), 2 bad scene or
// usage, 130 interrupted by SIGINT/SIGTERM. The record is valid in every case.
int run_scene(const RunOptions& options);

}  // namespace sphfsi::coordinator
