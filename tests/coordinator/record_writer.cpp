// Writes a record the way a run does: the real Recorder, driven without participants (their messages
// only decide what it writes). integration.record_kill stops it between any two of its file writes
// (kill_at_write.c) and reads what is left.
//
//   record_writer FILE PARTICLES FRAMES
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sphfsi/coordinator/recorder.hpp"

using namespace sphfsi;

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: record_writer FILE PARTICLES FRAMES\n");
        return 2;
    }
    const std::uint64_t n = std::strtoull(argv[2], nullptr, 10);
    const int frames = std::atoi(argv[3]);
    coordinator::RunMetadata meta{"scene.toml", "[run]\nend_time = 1\n", "", "test", "none", 3};
    coordinator::Recorder rec(argv[1], meta);
    rec.set_participant("fluid", "record_writer", Value{});
    protocol::InterfaceMesh mesh{protocol::F64Array::zeros(8, 2), protocol::I32Array::zeros(3, 4)};
    rec.set_interface(mesh);
    protocol::F64Array disp = protocol::F64Array::zeros(8, 2), force = protocol::F64Array::zeros(8, 2);

    protocol::F64Array position = protocol::F64Array::zeros(n, 2), pressure({n}, std::vector<double>(n));
    protocol::I32Array tag({n}, std::vector<std::int32_t>(n));
    protocol::F64Array y = protocol::F64Array::zeros(8, 2);
    for (int frame = 0; frame < frames; ++frame) {
        const double t = 1e-3 * frame;
        for (int w = 0; w < 5; ++w) {  // a few coupling windows per frame, as a run records
            disp.values[0] = t;
            rec.append_window({{"t", t + 2e-4 * w}, {"dt", 2e-4}, {"iterations", 1.0}}, &disp, &force);
        }
        for (std::uint64_t i = 0; i < n; ++i) {
            position(i, 0) = std::cos(t + i);
            position(i, 1) = std::sin(t + i);
            pressure.values[i] = t * i;
            tag.values[i] = static_cast<std::int32_t>((i + frame) % 7);
        }
        y.values[0] = t;
        rec.append_frame("fluid", t, {{"position", position}, {"pressure", pressure}, {"tag", tag}});
        rec.append_frame("structure", t, {{"y", y}});
    }
    rec.set_status("completed");
    return 0;
}
