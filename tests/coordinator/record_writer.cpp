// Writes a record the way a run does: the real Recorder, driven without participants (their messages
// only decide what it writes). integration.record_kill stops it between any two of its file writes
// (kill_at_write.c) and reads what is left.
//
//   record_writer FILE PARTICLES FRAMES
//   record_writer --deep-index FILE PARTICLES FRAMES
// The second writes fluid frames through the record's file layer alone (h5::create_file, Series, flush)
// with chunk index nodes of 4 entries instead of 64, so that 70 frames make indexes 4 levels deep; with
// each of the first 12 frames it also adds a dataset of a long name to /extras (more names than a group's
// name heap holds by default, added one flush after another).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "sphfsi/coordinator/recorder.hpp"

using namespace sphfsi;

namespace {
// What frame `frame` holds, the same in both modes (test_record_kill.py checks it).
void fill(int frame, protocol::F64Array& position, protocol::F64Array& pressure, protocol::I32Array& tag) {
    const double t = 1e-3 * frame;
    for (std::uint64_t i = 0; i < tag.values.size(); ++i) {
        position(i, 0) = std::cos(t + i);
        position(i, 1) = std::sin(t + i);
        pressure.values[i] = t * i;
        tag.values[i] = static_cast<std::int32_t>((i + frame) % 7);
    }
}

int write_deep_index(const std::string& path, std::uint64_t n, int frames) {
    namespace h5 = coordinator::h5;
    const std::string creating = path + ".creating";  // named once it reads back, as the Recorder does
    h5::Handle file = h5::create_file(creating, 2);
    h5::flush(file.get());
    std::filesystem::rename(creating, path);
    h5::Series position(file.get(), "/frames/fluid/position", {n, 2}, false, 1, false);
    h5::Series tag(file.get(), "/frames/fluid/tag", {n}, true, 1, true);
    h5::Series time(file.get(), "/frames/fluid/time", {}, false, 1, false);
    protocol::F64Array p = protocol::F64Array::zeros(n, 2), pressure({n}, std::vector<double>(n));
    protocol::I32Array k({n}, std::vector<std::int32_t>(n));
    for (int frame = 0; frame < frames; ++frame) {
        fill(frame, p, pressure, k);
        const double t = 1e-3 * frame;
        position.append(p.values.data(), 1);
        tag.append(k.values.data(), 1);
        time.append(&t, 1);
        if (frame < 12) {
            const double value = frame;
            h5::Series(file.get(), "/extras/a_dataset_whose_name_takes_room_" + std::to_string(frame), {}, false, 1, false)
                .append(&value, 1);
        }
        h5::flush(file.get());
    }
    return 0;
}
}  // namespace

int main(int argc, char** argv) {
    const bool deep = argc == 5 && std::string(argv[1]) == "--deep-index";
    if (argc != 4 && !deep) {
        std::fprintf(stderr, "usage: record_writer [--deep-index] FILE PARTICLES FRAMES\n");
        return 2;
    }
    argv += deep;
    const std::uint64_t n = std::strtoull(argv[2], nullptr, 10);
    const int frames = std::atoi(argv[3]);
    if (deep) return write_deep_index(argv[1], n, frames);
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
            force.values[1] = -t;  // not zero: a row counted before its data was written reads as zeros
            rec.append_window({{"t", t + 2e-4 * w}, {"dt", 2e-4}, {"iterations", 1.0}}, &disp, &force);
        }
        fill(frame, position, pressure, tag);
        y.values[0] = t;
        rec.append_frame("fluid", t, {{"position", position}, {"pressure", pressure}, {"tag", tag}});
        rec.append_frame("structure", t, {{"y", y}});
    }
    rec.set_status("completed");
    return 0;
}
