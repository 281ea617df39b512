#include "sphfsi/coordinator/checkpoint.hpp"

#include <fstream>
#include <msgpack.hpp>
#include <sstream>

#include "sphfsi/coordinator/replace_file.hpp"
#include "sphfsi/protocol/msgpack_writer.hpp"

namespace sphfsi::coordinator {
using protocol::F64Array;

namespace {
using Packer = protocol::Writer;

void pack_array(Packer& pk, const F64Array& a) {
    pk.pack_array(2);
    pk.pack(a.shape);
    pk.bin(a.values.data(), a.values.size() * sizeof(double));
}

F64Array unpack_array(const msgpack::object& o) {
    F64Array a;
    o.via.array.ptr[0].convert(a.shape);
    const auto& bin = o.via.array.ptr[1].via.bin;
    a.values.resize(bin.size / sizeof(double));
    std::memcpy(a.values.data(), bin.ptr, a.values.size() * sizeof(double));
    return a;
}
}  // namespace

void write_checkpoint(const std::filesystem::path& file, const Checkpoint& c) {
    Packer pk;
    pk.pack_array(15);
    pk.pack(std::string("sphfsi-checkpoint-1"));
    pk.pack(c.scene_file);
    pk.pack(c.scene_text);
    pk.pack(c.overrides);
    pk.f64(c.t);
    pk.pack(c.output_index);
    pk.pack(c.checkpoint_index);
    pk.pack(c.windows);
    pk.pack(c.steps);
    pk.f64(c.fluid_dt);
    pk.f64(c.structure_dt);
    pk.pack_array(6);
    pack_array(pk, c.interface.mesh.vertices);
    pk.pack(c.interface.mesh.cells.shape);
    pk.pack(c.interface.mesh.cells.values);
    pack_array(pk, c.interface.displacement);
    pack_array(pk, c.interface.velocity);
    pack_array(pk, c.interface.previous_displacement);
    pk.pack_array(7);
    pack_array(pk, c.interface.force);
    pk.f64(c.interface.previous_dt);
    pack_array(pk, c.interface.fluid_displacement);
    pk.f64(c.interface.work_total);
    pk.f64(c.interface.created_total);
    pk.f64(c.interface.fluid_energy);
    pk.f64(c.interface.total_energy);
    pk.pack_map(static_cast<std::uint32_t>(c.states.size()));
    for (const auto& [role, bytes] : c.states) {
        pk.pack(role);
        pk.bin(bytes.data(), bytes.size());
    }
    pk.pack_array(2);
    pk.f64(c.loop_wall_s);
    pk.f64(c.loop_cpu_s);
    replace_file(file, pk.bytes(), "checkpoint");
}

Checkpoint read_checkpoint(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error("no checkpoint at " + file.string() + " (was the run started with a checkpoint interval?)");
    std::ostringstream s;
    s << in.rdbuf();
    std::string bytes = s.str();
    try {
        auto oh = msgpack::unpack(bytes.data(), bytes.size());
        const auto& a = oh.get().via.array;
        // 14 entries before the loop times were added as the 15th (2026-11-27).
        if (a.size < 14 || a.size > 15 || a.ptr[0].as<std::string>() != "sphfsi-checkpoint-1")
            throw std::runtime_error("not a checkpoint of this version");
        Checkpoint c;
        c.scene_file = a.ptr[1].as<std::string>();
        c.scene_text = a.ptr[2].as<std::string>();
        c.overrides = a.ptr[3].as<std::vector<std::string>>();
        c.t = a.ptr[4].as<double>();
        c.output_index = a.ptr[5].as<std::uint64_t>();
        c.checkpoint_index = a.ptr[6].as<std::uint64_t>();
        c.windows = a.ptr[7].as<std::uint64_t>();
        c.steps = a.ptr[8].as<std::uint64_t>();
        c.fluid_dt = a.ptr[9].as<double>();
        c.structure_dt = a.ptr[10].as<double>();
        const auto& i = a.ptr[11].via.array;
        c.interface.mesh.vertices = unpack_array(i.ptr[0]);
        i.ptr[1].convert(c.interface.mesh.cells.shape);
        i.ptr[2].convert(c.interface.mesh.cells.values);
        c.interface.displacement = unpack_array(i.ptr[3]);
        c.interface.velocity = unpack_array(i.ptr[4]);
        c.interface.previous_displacement = unpack_array(i.ptr[5]);
        const auto& coupling = a.ptr[12].via.array;
        c.interface.force = unpack_array(coupling.ptr[0]);
        c.interface.previous_dt = coupling.ptr[1].as<double>();
        // (Checkpoints written before the interface energy balance lack it: the fluid's displacement then
        // starts from the structure's and the balance from zero.)
        c.interface.fluid_displacement = coupling.size > 2 ? unpack_array(coupling.ptr[2]) : c.interface.displacement;
        if (coupling.size > 5) {
            c.interface.work_total = coupling.ptr[3].as<double>();
            c.interface.created_total = coupling.ptr[4].as<double>();
            c.interface.fluid_energy = coupling.ptr[5].as<double>();
        }
        // Else from the next window. Builds before 2026-11-27 wrote 0 for "not known yet".
        if (coupling.size > 6 && coupling.ptr[6].as<double>() != 0.0) c.interface.total_energy = coupling.ptr[6].as<double>();
        const auto& m = a.ptr[13].via.map;
        for (std::uint32_t k = 0; k < m.size; ++k) {
            const auto& bin = m.ptr[k].val.via.bin;
            const auto* p = reinterpret_cast<const std::uint8_t*>(bin.ptr);
            c.states[m.ptr[k].key.as<std::string>()] = std::vector<std::uint8_t>(p, p + bin.size);
        }
        if (a.size > 14) {
            if (a.ptr[14].type != msgpack::type::ARRAY || a.ptr[14].via.array.size != 2)
                throw std::runtime_error("the loop times are not an array of two numbers");
            const auto& loop = a.ptr[14].via.array;
            c.loop_wall_s = loop.ptr[0].as<double>();
            c.loop_cpu_s = loop.ptr[1].as<double>();
        }
        return c;
    } catch (const std::exception& e) {
        throw std::runtime_error(file.string() + ": unreadable checkpoint: " + e.what());
    }
}

}  // namespace sphfsi::coordinator
