// checkpoint.bin (coordinator/src/checkpoint.cpp): what is written reads back whole, and a damaged or foreign
// file is refused with "unreadable checkpoint", never read past its end. A one-byte file and a checkpoint
// whose interface was an empty array had crashed the coordinator (segmentation fault; a review, 2026-11-27).
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <msgpack.hpp>

#include "sphfsi/coordinator/checkpoint.hpp"

using namespace sphfsi;
using namespace sphfsi::coordinator;

namespace {

std::filesystem::path scratch(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("sphfsi_test_checkpoint_" + std::to_string(::getpid()) + "_" + name);
}

std::string read_bytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const std::filesystem::path& file, const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

// A checkpoint of a two-cell interface, every field set to something other than its default.
Checkpoint sample() {
    Checkpoint c;
    c.scene_file = "scene.toml";
    c.scene_text = "[run]\nend_time = 1.0\n";
    c.overrides = {"run.end_time=1.0"};
    c.t = 0.25;
    c.output_index = 6;
    c.checkpoint_index = 1;
    c.windows = 25;
    c.steps = 250;
    c.fluid_dt = 1e-4;
    c.structure_dt = 1e-3;
    protocol::InterfaceMesh mesh{protocol::F64Array({6, 2}, {0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1}),
                                 protocol::I32Array({2, 4}, {0, 1, 4, 3, 1, 2, 5, 4})};
    c.interface.reset(mesh);
    // Each array different, so that a reader that swapped two of them fails the round trip.
    for (std::size_t k = 0; k < 12; ++k) {
        const double x = static_cast<double>(k) + 1.0;
        c.interface.displacement.values[k] = 1e-3 * x;
        c.interface.velocity.values[k] = 2e-3 * x;
        c.interface.previous_displacement.values[k] = 3e-3 * x;
        c.interface.force.values[k] = -x;
        c.interface.fluid_displacement.values[k] = 4e-3 * x;
    }
    c.interface.previous_dt = 1e-3;
    c.interface.work_total = 0.5;
    c.interface.created_total = 0.25;
    c.interface.fluid_energy = 7.0;
    c.interface.total_energy = 2.0;
    // Two IQN-ILS windows of secant pairs: V columns of 12 values (the displacements), W of 24.
    for (int w = 0; w < 2; ++w) {
        SecantWindow s;
        for (int j = 0; j <= w; ++j) {
            s.V.emplace_back(12, 0.1 * (w + 1) + j);
            s.W.emplace_back(24, -0.2 * (w + 1) - j);
        }
        c.interface.secants.push_back(s);
    }
    c.states = {{"fluid", {1, 2, 3}}, {"structure", {4, 5}}};
    c.loop_wall_s = 3.5;
    c.loop_cpu_s = 3.0;
    return c;
}

void check_refused(const std::filesystem::path& file) {
    try {
        read_checkpoint(file);
        FAIL("a damaged checkpoint was read");
    } catch (const std::runtime_error& e) {
        CHECK(std::string(e.what()).find("unreadable checkpoint") != std::string::npos);
    }
}

}  // namespace

TEST_SUITE("checkpoint") {
    TEST_CASE("a checkpoint reads back as it was written") {
        const auto file = scratch("roundtrip");
        const Checkpoint c = sample();
        write_checkpoint(file, c);
        const Checkpoint r = read_checkpoint(file);
        CHECK(r.scene_text == c.scene_text);
        CHECK(r.overrides == c.overrides);
        CHECK(r.t == c.t);
        CHECK(r.output_index == c.output_index);
        CHECK(r.windows == c.windows);
        CHECK(r.scene_file == c.scene_file);
        CHECK(r.checkpoint_index == c.checkpoint_index);
        CHECK(r.steps == c.steps);
        CHECK(r.fluid_dt == c.fluid_dt);
        CHECK(r.structure_dt == c.structure_dt);
        CHECK(r.interface.mesh == c.interface.mesh);
        CHECK(r.interface.displacement == c.interface.displacement);
        CHECK(r.interface.velocity == c.interface.velocity);
        CHECK(r.interface.previous_displacement == c.interface.previous_displacement);
        CHECK(r.interface.force == c.interface.force);
        CHECK(r.interface.fluid_displacement == c.interface.fluid_displacement);
        CHECK(r.interface.previous_dt == c.interface.previous_dt);
        CHECK(r.interface.work_total == c.interface.work_total);
        CHECK(r.interface.created_total == c.interface.created_total);
        CHECK(r.interface.fluid_energy == c.interface.fluid_energy);
        CHECK(r.interface.total_energy == c.interface.total_energy);
        REQUIRE(r.interface.secants.size() == 2);
        for (std::size_t w = 0; w < 2; ++w) {
            CHECK(r.interface.secants[w].V == c.interface.secants[w].V);
            CHECK(r.interface.secants[w].W == c.interface.secants[w].W);
        }
        CHECK(r.states == c.states);
        CHECK(r.loop_wall_s == c.loop_wall_s);
        CHECK(r.loop_cpu_s == c.loop_cpu_s);
        // A baseline of exactly 0 is a baseline, not "unknown" (NaN), which reads back as NaN.
        Checkpoint zero = sample();
        zero.interface.total_energy = 0.0;
        write_checkpoint(file, zero);
        CHECK(read_checkpoint(file).interface.total_energy == 0.0);
        zero.interface.total_energy = std::numeric_limits<double>::quiet_NaN();
        write_checkpoint(file, zero);
        CHECK(std::isnan(read_checkpoint(file).interface.total_energy));
        // A fluid alone has no interface: its arrays have no shape at all.
        write_checkpoint(file, Checkpoint{});
        CHECK(read_checkpoint(file).interface.mesh.vertices.values.empty());
        std::filesystem::remove(file);
    }

    TEST_CASE("a checkpoint cut short at any byte is refused") {
        const auto file = scratch("cut");
        write_checkpoint(file, sample());
        const std::string whole = read_bytes(file);
        for (std::size_t n = 0; n < whole.size(); ++n) {
            write_bytes(file, whole.substr(0, n));
            CAPTURE(n);
            check_refused(file);
        }
        std::filesystem::remove(file);
    }

    TEST_CASE("a damaged checkpoint is refused, never read past its end") {
        const auto file = scratch("damaged");
        // A single positive integer (the reviewer's one-byte file), a version string alone, and a checkpoint
        // whose interface (its 12th entry) is an empty array.
        write_bytes(file, std::string(1, '\x0e'));
        check_refused(file);
        write_bytes(file, "\xb3sphfsi-checkpoint-1");
        check_refused(file);
        write_checkpoint(file, sample());
        std::string bytes = read_bytes(file);
        {  // The sample with its 12th entry (the interface) replaced by [], built as such: the byte loop below
           // makes it too, but would pass a file that was read.
            const msgpack::object_handle h = msgpack::unpack(bytes.data(), bytes.size());
            const msgpack::object& top = h.get();
            REQUIRE(top.type == msgpack::type::ARRAY);
            const std::uint32_t n = top.via.array.size;  // 15 entries since the loop times
            REQUIRE(n > 11);
            msgpack::sbuffer out;
            msgpack::packer<msgpack::sbuffer> pk(out);
            pk.pack_array(n);
            for (std::uint32_t k = 0; k < n; ++k)
                if (k == 11) pk.pack_array(0);
                else pk.pack(top.via.array.ptr[k]);
            write_bytes(file, std::string(out.data(), out.size()));
            check_refused(file);
        }
        // Every single byte changed to each of a few values that change a type (nil, an empty array or
        // map, a large positive integer): refused or read, never a crash.
        const std::string original = bytes;
        for (std::size_t at = 0; at < original.size(); ++at)
            for (unsigned char b : {0xc0, 0x90, 0x80, 0x7f}) {
                bytes = original;
                bytes[at] = static_cast<char>(b);
                write_bytes(file, bytes);
                try {
                    read_checkpoint(file);
                } catch (const std::runtime_error& e) {
                    CHECK(std::string(e.what()).find("unreadable checkpoint") != std::string::npos);
                }
            }
        std::filesystem::remove(file);
    }

    TEST_CASE("interface arrays that do not match the mesh are refused") {
        const auto file = scratch("mismatch");
        Checkpoint c = sample();
        c.interface.velocity = protocol::F64Array::zeros(5, 2);  // 5 vertices for a mesh of 6
        write_checkpoint(file, c);
        check_refused(file);
        c = sample();
        c.interface.mesh.cells.values[3] = 6;  // no vertex 6
        write_checkpoint(file, c);
        check_refused(file);
        c = sample();
        c.interface.secants[1].W[0].pop_back();  // a W column one value short
        write_checkpoint(file, c);
        check_refused(file);
        c = sample();
        c.interface.secants[0].V.push_back(c.interface.secants[0].V[0]);  // a V column without its W
        write_checkpoint(file, c);
        check_refused(file);
        std::filesystem::remove(file);
    }
}
