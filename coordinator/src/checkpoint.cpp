#include "sphfsi/coordinator/checkpoint.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <msgpack.hpp>
#include <sstream>
#include <stdexcept>
#include <utility>

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

// Every entry is checked for its type and size before it is read: a damaged or foreign file is refused
// with what was wrong, never read past its end (a one-byte file had crashed the coordinator).
const msgpack::object_array& array_of(const msgpack::object& o, std::uint32_t min, std::uint32_t max, const char* what) {
    if (o.type != msgpack::type::ARRAY || o.via.array.size < min || o.via.array.size > max)
        throw std::runtime_error(std::string(what) + " is not an array of " + std::to_string(min) +
                                 (max > min ? " to " + std::to_string(max) : std::string()) + " entries");
    return o.via.array;
}

const msgpack::object_bin& bin_of(const msgpack::object& o, const char* what) {
    if (o.type != msgpack::type::BIN) throw std::runtime_error(std::string(what) + " is not binary data");
    return o.via.bin;
}

// The number of values a shape holds (none for no shape: a fluid alone has no interface), or an error if the
// shape's product overflows.
std::uint64_t values_in(const std::vector<std::uint64_t>& shape, const char* what) {
    if (shape.empty()) return 0;
    std::uint64_t n = 1;
    for (std::uint64_t d : shape) {
        if (d != 0 && n > UINT64_MAX / d) throw std::runtime_error(std::string(what) + ": the shape overflows");
        n *= d;
    }
    return n;
}

F64Array unpack_array(const msgpack::object& o, const char* what) {
    const auto& a = array_of(o, 2, 2, what);
    F64Array r;
    a.ptr[0].convert(r.shape);
    const auto& bin = bin_of(a.ptr[1], what);
    if (bin.size % sizeof(double) != 0 || bin.size / sizeof(double) != values_in(r.shape, what))
        throw std::runtime_error(std::string(what) + ": " + std::to_string(bin.size) + " bytes of data for its shape");
    r.values.resize(bin.size / sizeof(double));
    if (bin.size > 0) std::memcpy(r.values.data(), bin.ptr, bin.size);
    return r;
}

// IQN-ILS's secant history (session.hpp): per window, its V and W columns as doubles.
void pack_secants(Packer& pk, const SecantHistory& h) {
    pk.pack_array(static_cast<std::uint32_t>(h.size()));
    for (const SecantWindow& w : h) {
        pk.pack_array(2);
        for (const auto* columns : {&w.V, &w.W}) {
            pk.pack_array(static_cast<std::uint32_t>(columns->size()));
            for (const auto& c : *columns) pk.bin(c.data(), c.size() * sizeof(double));
        }
    }
}

// `nd`: the interface's displacement values (2 per vertex): a V column has nd, a W column 2 nd.
SecantHistory unpack_secants(const msgpack::object& o, std::size_t nd) {
    SecantHistory h;
    const auto& windows = array_of(o, 0, UINT32_MAX, "the IQN-ILS secant history");
    for (std::uint32_t k = 0; k < windows.size; ++k) {
        const auto& w = array_of(windows.ptr[k], 2, 2, "an IQN-ILS secant window");
        SecantWindow out;
        for (std::uint32_t side = 0; side < 2; ++side) {  // V, then W: twice as long (velocities too)
            auto& columns = side == 0 ? out.V : out.W;
            const std::size_t length = (side + 1) * nd;
            const auto& list = array_of(w.ptr[side], 1, UINT32_MAX, "IQN-ILS secant columns");
            for (std::uint32_t j = 0; j < list.size; ++j) {
                const auto& bin = bin_of(list.ptr[j], "an IQN-ILS secant column");
                if (bin.size != length * sizeof(double))
                    throw std::runtime_error("an IQN-ILS secant column has " + std::to_string(bin.size) + " bytes, not " +
                                             std::to_string(length * sizeof(double)) + " for this interface");
                std::vector<double> c(length);
                if (length > 0) std::memcpy(c.data(), bin.ptr, bin.size);
                columns.push_back(std::move(c));
            }
        }
        if (out.V.size() != out.W.size()) throw std::runtime_error("an IQN-ILS secant window has unequal V and W columns");
        h.push_back(std::move(out));
    }
    return h;
}

// The interface arrays are per vertex, and the cells index the vertices.
void check_interface(const InterfaceState& s) {
    const std::size_t n = s.mesh.vertices.values.size();
    const std::pair<const F64Array*, const char*> per_vertex[] = {
        {&s.displacement, "displacement"}, {&s.velocity, "velocity"}, {&s.previous_displacement, "previous displacement"},
        {&s.force, "force"}, {&s.fluid_displacement, "fluid displacement"}};
    for (const auto& [array, what] : per_vertex)
        if (array->values.size() != n)
            throw std::runtime_error(std::string("the interface ") + what + " has " + std::to_string(array->values.size()) +
                                     " values for " + std::to_string(n) + " vertex coordinates");
    if (s.mesh.cells.values.size() != values_in(s.mesh.cells.shape, "the interface cells"))
        throw std::runtime_error("the interface cells do not fill their shape");
    for (std::int32_t v : s.mesh.cells.values)
        if (v < 0 || 2 * static_cast<std::uint64_t>(v) >= n)
            throw std::runtime_error("an interface cell names vertex " + std::to_string(v) + ", which does not exist");
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
    pk.pack_array(8);
    pack_array(pk, c.interface.force);
    pk.f64(c.interface.previous_dt);
    pack_array(pk, c.interface.fluid_displacement);
    pk.f64(c.interface.work_total);
    pk.f64(c.interface.created_total);
    pk.f64(c.interface.fluid_energy);
    pk.f64(c.interface.total_energy);
    pack_secants(pk, c.interface.secants);
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
        const auto& top = oh.get();
        // 14 entries before the loop times were added as the 15th (2026-11-27).
        if (top.type != msgpack::type::ARRAY || top.via.array.size < 14 || top.via.array.size > 15 ||
            top.via.array.ptr[0].type != msgpack::type::STR || top.via.array.ptr[0].as<std::string>() != "sphfsi-checkpoint-1")
            throw std::runtime_error("not a checkpoint of this version");
        const auto& a = top.via.array;
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
        const auto& i = array_of(a.ptr[11], 6, 6, "the interface");
        c.interface.mesh.vertices = unpack_array(i.ptr[0], "the interface vertices");
        i.ptr[1].convert(c.interface.mesh.cells.shape);
        i.ptr[2].convert(c.interface.mesh.cells.values);
        c.interface.displacement = unpack_array(i.ptr[3], "the interface displacement");
        c.interface.velocity = unpack_array(i.ptr[4], "the interface velocity");
        c.interface.previous_displacement = unpack_array(i.ptr[5], "the previous interface displacement");
        const auto& coupling = array_of(a.ptr[12], 2, 8, "the coupling state");
        c.interface.force = unpack_array(coupling.ptr[0], "the interface force");
        c.interface.previous_dt = coupling.ptr[1].as<double>();
        // (Checkpoints written before the interface energy balance lack it: the fluid's displacement then
        // starts from the structure's and the balance from zero.)
        c.interface.fluid_displacement = coupling.size > 2 ? unpack_array(coupling.ptr[2], "the fluid's interface displacement")
                                                             : c.interface.displacement;
        if (coupling.size > 5) {
            c.interface.work_total = coupling.ptr[3].as<double>();
            c.interface.created_total = coupling.ptr[4].as<double>();
            c.interface.fluid_energy = coupling.ptr[5].as<double>();
        }
        // NaN: from the next window. Builds before 2026-11-27 wrote 0 for "not known yet" and no secant history
        // (their 7 entries); a baseline of exactly 0 is kept from the 8-entry layout on (a review).
        if (coupling.size > 7) c.interface.total_energy = coupling.ptr[6].as<double>();
        else if (coupling.size > 6 && coupling.ptr[6].as<double>() != 0.0) c.interface.total_energy = coupling.ptr[6].as<double>();
        check_interface(c.interface);
        if (coupling.size > 7) c.interface.secants = unpack_secants(coupling.ptr[7], c.interface.displacement.values.size());
        if (a.ptr[13].type != msgpack::type::MAP) throw std::runtime_error("the participants' states are not a map");
        const auto& m = a.ptr[13].via.map;
        for (std::uint32_t k = 0; k < m.size; ++k) {
            const auto& bin = bin_of(m.ptr[k].val, "a participant's state");
            const auto* p = reinterpret_cast<const std::uint8_t*>(bin.ptr);
            c.states[m.ptr[k].key.as<std::string>()] = std::vector<std::uint8_t>(p, p + bin.size);
        }
        if (a.size > 14) {
            const auto& loop = array_of(a.ptr[14], 2, 2, "the loop times");
            c.loop_wall_s = loop.ptr[0].as<double>();
            c.loop_cpu_s = loop.ptr[1].as<double>();
        }
        return c;
    } catch (const std::exception& e) {
        throw std::runtime_error(file.string() + ": unreadable checkpoint: " + e.what());
    }
}

}  // namespace sphfsi::coordinator
