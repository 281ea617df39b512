#include "sphfsi/protocol/codec.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <msgpack.hpp>

#include "sphfsi/protocol/msgpack_writer.hpp"

namespace sphfsi::protocol {
static_assert(std::endian::native == std::endian::little, "blobs are little-endian; add byte swapping for this host");

namespace {
using Packer = Writer;

// ---------- text ----------
// The length of the well-formed UTF-8 sequence that starts at s[i], or 0 if none starts there (RFC 3629:
// no overlong forms, no surrogates, nothing above U+10FFFF; what a strict decoder such as Python's accepts).
std::size_t utf8_sequence(std::string_view s, std::size_t i) {
    auto at = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = at(i);
    if (c < 0x80) return 1;
    std::size_t n = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
    if (c >= 0xC2 && c <= 0xDF) n = 2;
    else if (c >= 0xE0 && c <= 0xEF) n = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
    else if (c >= 0xF0 && c <= 0xF4) n = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
    else return 0;
    if (n > s.size() - i || at(i + 1) < lo || at(i + 1) > hi) return 0;
    for (std::size_t k = 2; k < n; ++k)
        if ((at(i + k) & 0xC0) != 0x80) return 0;
    return n;
}

// `s` with each byte outside well-formed UTF-8 (and, if `controls`, each ASCII control character) as \xNN.
std::string escaped(std::string_view s, bool controls, std::size_t max_bytes) {
    static const char hex[] = "0123456789abcdef";
    std::string out;
    out.reserve(std::min(s.size(), max_bytes) + 8);
    for (std::size_t i = 0; i < s.size();) {
        if (i >= max_bytes) {
            out += "...";
            break;
        }
        const std::size_t n = utf8_sequence(s, i);
        const auto c = static_cast<unsigned char>(s[i]);
        auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[i + k]); };
        // Bidirectional embeddings and isolates (U+202A-202E, U+2066-2069) reorder how the rest of a log line
        // is displayed: a quoted name could make the line read as something else.
        const bool bidi = controls && n == 3 && c == 0xE2 &&
                          ((byte(1) == 0x80 && byte(2) >= 0xAA && byte(2) <= 0xAE) || (byte(1) == 0x81 && byte(2) >= 0xA6 && byte(2) <= 0xA9));
        const std::size_t escape = bidi ? 3 : (n == 0 || (controls && (c < 0x20 || c == 0x7F))) ? 1 : 0;
        if (escape == 0) {
            out.append(s, i, n);
            i += n;
            continue;
        }
        for (std::size_t k = 0; k < escape; ++k) (out += "\\x") += {hex[byte(k) >> 4], hex[byte(k) & 0xF]};
        i += escape;
    }
    return out;
}

// Every string the codec writes goes through here, so that no message it encodes carries a str that is not
// UTF-8 (docs/protocol.md, "Envelope"), whatever went into it: an ERROR text quoting a peer's bytes, a token
// or name from a command line. Valid text, the only kind the programs produce, is written unchanged.
void pack_text(Packer& pk, std::string_view s) {
    if (is_utf8(s)) pk.pack(s);
    else pk.pack(escaped(s, false, s.size()));
}

// ---------- encoding ----------
void pack_value(Packer& pk, const Value& v) {
    std::visit(
        [&](const auto& x) {
            using T = std::decay_t<decltype(x)>;
            if constexpr (std::is_same_v<T, std::monostate>) pk.pack_nil();
            else if constexpr (std::is_same_v<T, bool>) x ? pk.pack_true() : pk.pack_false();
            else if constexpr (std::is_same_v<T, std::int64_t>) pk.pack_int64(x);
            else if constexpr (std::is_same_v<T, double>) pk.f64(x);
            else if constexpr (std::is_same_v<T, std::string>) pack_text(pk, x);
            else if constexpr (std::is_same_v<T, Value::Array>) {
                pk.pack_array(static_cast<std::uint32_t>(x.size()));
                for (const Value& e : x) pack_value(pk, e);
            } else {
                pk.pack_map(static_cast<std::uint32_t>(x.size()));
                for (const auto& [k, e] : x) {
                    pack_text(pk, k);
                    pack_value(pk, e);
                }
            }
        },
        v.data());
}

template <class T>
void pack_array(Packer& pk, const NdArray<T>& a) {
    pk.pack_map(3);
    pk.pack("dtype");
    pk.pack(std::is_same_v<T, double> ? "f8" : "i4");
    pk.pack("shape");
    pk.pack_array(static_cast<std::uint32_t>(a.shape.size()));
    for (auto s : a.shape) pk.pack_uint64(s);
    pk.pack("data");
    pk.bin(a.values.data(), a.values.size() * sizeof(T));
}

void pack_field(Packer& pk, const Field& f) {
    std::visit([&](const auto& a) { pack_array(pk, a); }, f);
}

void pack_fields(Packer& pk, const Fields& fields) {
    pk.pack_map(static_cast<std::uint32_t>(fields.size()));
    for (const auto& [name, f] : fields) {
        pack_text(pk, name);
        pack_field(pk, f);
    }
}

void pack_mesh(Packer& pk, const std::optional<InterfaceMesh>& mesh) {
    if (!mesh) return pk.pack_nil(), void();
    pk.pack_map(2);
    pk.pack("vertices");
    pack_array(pk, mesh->vertices);
    pk.pack("cells");
    pack_array(pk, mesh->cells);
}

void pack_bytes(Packer& pk, const std::vector<std::uint8_t>& b) { pk.bin(b.data(), b.size()); }

struct BodyPacker {
    Packer& pk;
    std::uint32_t version;  // of the message: a body's keys depend on it (INIT, READY: interface_state from 2)
    void key(const char* k) { pk.pack(std::string_view(k)); }
    void operator()(const Empty&) { pk.pack_map(0); }
    void operator()(const Hello& h) {
        pk.pack_map(6);
        key("name"); pack_text(pk, h.name);
        key("kind"); pack_text(pk, h.kind);
        key("version_min"); pk.pack_uint32(h.version_min);
        key("version_max"); pk.pack_uint32(h.version_max);
        key("software"); pack_text(pk, h.software);
        key("pid"); pk.pack_int64(h.pid);
    }
    void operator()(const Welcome& w) {
        pk.pack_map(3);
        key("version"); pk.pack_uint32(w.version);
        key("heartbeat_s"); pk.f64(w.heartbeat_s);
        key("timeout_s"); pk.f64(w.timeout_s);
    }
    void operator()(const InitRequest& r) {
        pk.pack_map(version >= 2 ? 5 : 4);
        key("config"); pack_value(pk, r.config);
        key("t0"); pk.f64(r.t0);
        key("interface"); pack_mesh(pk, r.interface);
        key("state"); pack_bytes(pk, r.state);
        if (version >= 2) { key("interface_state"); pack_fields(pk, r.interface_state); }
    }
    void operator()(const InitReply& r) {
        pk.pack_map(version >= 2 ? 4 : 3);
        key("dt_wanted"); pk.f64(r.dt_wanted);
        key("interface"); pack_mesh(pk, r.interface);
        key("info"); pack_value(pk, r.info.is_null() ? Value(Value::Table{}) : r.info);
        if (version >= 2) { key("interface_state"); pack_fields(pk, r.interface_state); }
    }
    void operator()(const AdvanceRequest& r) {
        pk.pack_map(5);
        key("t"); pk.f64(r.t);
        key("dt"); pk.f64(r.dt);
        key("substeps"); pk.pack_uint32(r.substeps);
        key("iteration"); pk.pack_uint32(r.iteration);
        key("inputs"); pack_fields(pk, r.inputs);
    }
    void operator()(const AdvanceReply& r) {
        pk.pack_map(7);
        key("t"); pk.f64(r.t);
        key("dt_wanted"); pk.f64(r.dt_wanted);
        key("outputs"); pack_fields(pk, r.outputs);
        key("substeps"); pk.pack_uint32(r.substeps);
        key("solver_iterations"); pk.pack_uint32(r.solver_iterations);
        key("compute_s"); pk.f64(r.compute_s);
        key("stats"); pack_value(pk, r.stats.is_null() ? Value(Value::Table{}) : r.stats);
    }
    void operator()(const Frame& f) {
        pk.pack_map(2);
        key("t"); pk.f64(f.t);
        key("fields"); pack_fields(pk, f.fields);
    }
    void operator()(const State& s) {
        pk.pack_map(2);
        key("t"); pk.f64(s.t);
        key("state"); pack_bytes(pk, s.bytes);
    }
    void operator()(const Heartbeat& h) {
        pk.pack_map(1);
        key("progress"); pk.pack_uint64(h.progress);
    }
    void operator()(const ErrorReply& e) {
        pk.pack_map(3);
        key("code"); pack_text(pk, e.code);
        key("message"); pack_text(pk, e.message);
        key("in_reply_to"); pk.pack_uint64(e.in_reply_to);
    }
};

// ---------- decoding ----------
[[noreturn]] void bad(const std::string& why) { throw ProtocolError("bad_message", why); }

// A checked view of one msgpack map: every key must be consumed, so unknown keys are refused.
class MapReader {
public:
    MapReader(const msgpack::object& o, std::string where) : where_(std::move(where)) {
        if (o.type != msgpack::type::MAP) bad(where_ + " must be a map");
        map_ = o.via.map;
        used_.assign(map_.size, false);
        for (std::uint32_t i = 0; i < map_.size; ++i)
            if (map_.ptr[i].key.type != msgpack::type::STR) bad(where_ + " has a key that is not a string");
    }
    const msgpack::object& need(std::string_view key) {
        if (const msgpack::object* o = find(key)) return *o;
        bad(where_ + " lacks the key '" + std::string(key) + "'");
    }
    const msgpack::object* find(std::string_view key) {
        for (std::uint32_t i = 0; i < map_.size; ++i) {
            const auto& k = map_.ptr[i].key.via.str;
            if (std::string_view(k.ptr, k.size) == key) {
                if (used_[i]) bad(where_ + " repeats the key '" + std::string(key) + "'");
                used_[i] = true;
                return &map_.ptr[i].val;
            }
        }
        return nullptr;
    }
    // Refuses keys nobody asked for: the protocol version covers every field, so an extra key is a bug.
    void finish() {
        for (std::uint32_t i = 0; i < map_.size; ++i)
            if (!used_[i]) {
                const auto& k = map_.ptr[i].key.via.str;
                bad(where_ + " has the unknown or repeated key '" + printable({k.ptr, k.size}) + "'");
            }
    }
    const std::string& where() const { return where_; }

private:
    msgpack::object_map map_{};
    std::string where_;
    std::vector<bool> used_;
};

std::string need_string(const msgpack::object& o, const std::string& what) {
    if (o.type != msgpack::type::STR) bad(what + " must be a string");
    return std::string(o.via.str.ptr, o.via.str.size);
}
std::uint64_t need_uint(const msgpack::object& o, const std::string& what) {
    if (o.type == msgpack::type::POSITIVE_INTEGER) return o.via.u64;
    bad(what + " must be a non-negative integer");
}
std::uint32_t need_u32(const msgpack::object& o, const std::string& what) {
    std::uint64_t u = need_uint(o, what);
    if (u > std::numeric_limits<std::uint32_t>::max()) bad(what + " is larger than 2^32-1");
    return static_cast<std::uint32_t>(u);
}
std::int64_t need_int(const msgpack::object& o, const std::string& what) {
    if (o.type == msgpack::type::NEGATIVE_INTEGER) return o.via.i64;
    if (o.type == msgpack::type::POSITIVE_INTEGER && o.via.u64 <= std::uint64_t(std::numeric_limits<std::int64_t>::max()))
        return static_cast<std::int64_t>(o.via.u64);
    bad(what + " must be an integer");
}
// Integers are accepted where a float is expected: other languages often pack 0 as an int.
double need_double(const msgpack::object& o, const std::string& what) {
    switch (o.type) {
        case msgpack::type::FLOAT32:
        case msgpack::type::FLOAT64: return o.via.f64;
        case msgpack::type::POSITIVE_INTEGER: return static_cast<double>(o.via.u64);
        case msgpack::type::NEGATIVE_INTEGER: return static_cast<double>(o.via.i64);
        default: bad(what + " must be a number");
    }
}
std::vector<std::uint8_t> need_bytes(const msgpack::object& o, const std::string& what) {
    if (o.type != msgpack::type::BIN) bad(what + " must be binary (msgpack bin)");
    const auto* p = reinterpret_cast<const std::uint8_t*>(o.via.bin.ptr);
    return {p, p + o.via.bin.size};
}

Value to_value(const msgpack::object& o, const std::string& what) {
    switch (o.type) {
        case msgpack::type::NIL: return Value();
        case msgpack::type::BOOLEAN: return Value(o.via.boolean);
        case msgpack::type::POSITIVE_INTEGER:
        case msgpack::type::NEGATIVE_INTEGER: return Value(need_int(o, what));
        case msgpack::type::FLOAT32:
        case msgpack::type::FLOAT64: return Value(o.via.f64);
        case msgpack::type::STR: return Value(std::string(o.via.str.ptr, o.via.str.size));
        case msgpack::type::ARRAY: {
            Value::Array a;
            a.reserve(o.via.array.size);
            for (std::uint32_t i = 0; i < o.via.array.size; ++i) a.push_back(to_value(o.via.array.ptr[i], what));
            return Value(std::move(a));
        }
        case msgpack::type::MAP: {
            Value::Table t;
            for (std::uint32_t i = 0; i < o.via.map.size; ++i) {
                std::string k = need_string(o.via.map.ptr[i].key, what + " key");
                if (!t.emplace(k, to_value(o.via.map.ptr[i].val, what + "." + printable(k))).second)
                    bad(what + " repeats the key '" + printable(k) + "'");
            }
            return Value(std::move(t));
        }
        default: bad(what + " holds a value of a type configuration cannot have (bin or ext)");
    }
}

template <class T>
NdArray<T> read_array(const msgpack::object& o, const std::string& what) {
    MapReader m(o, what);
    std::string dtype = need_string(m.need("dtype"), what + ".dtype");
    const char* want = std::is_same_v<T, double> ? "f8" : "i4";
    if (dtype != want) bad(what + ".dtype is \"" + printable(dtype) + "\", expected \"" + want + "\"");
    const auto& shape = m.need("shape");
    if (shape.type != msgpack::type::ARRAY || shape.via.array.size < 1 || shape.via.array.size > 4)
        bad(what + ".shape must be an array of 1 to 4 sizes");
    NdArray<T> a;
    std::uint64_t count = 1;
    for (std::uint32_t i = 0; i < shape.via.array.size; ++i) {
        std::uint64_t s = need_uint(shape.via.array.ptr[i], what + ".shape");
        if (s != 0 && count > std::numeric_limits<std::uint64_t>::max() / sizeof(T) / s) bad(what + ".shape overflows");
        count *= s;
        a.shape.push_back(s);
    }
    const auto& data = m.need("data");
    if (data.type != msgpack::type::BIN) bad(what + ".data must be binary (msgpack bin)");
    if (data.via.bin.size != count * sizeof(T))
        bad(what + ".data has " + std::to_string(data.via.bin.size) + " bytes, shape needs " +
            std::to_string(count * sizeof(T)));
    a.values.resize(count);
    if (count) std::memcpy(a.values.data(), data.via.bin.ptr, count * sizeof(T));
    m.finish();
    return a;
}

Field read_field(const msgpack::object& o, const std::string& what) {
    MapReader peek(o, what);
    std::string dtype = need_string(peek.need("dtype"), what + ".dtype");
    if (dtype == "f8") return read_array<double>(o, what);
    if (dtype == "i4") return read_array<std::int32_t>(o, what);
    bad(what + ".dtype \"" + printable(dtype) + "\" is not one of \"f8\", \"i4\"");
}

Fields read_fields(const msgpack::object& o, const std::string& what) {
    if (o.type != msgpack::type::MAP) bad(what + " must be a map of arrays");
    Fields out;
    for (std::uint32_t i = 0; i < o.via.map.size; ++i) {
        std::string name = need_string(o.via.map.ptr[i].key, what + " key");
        if (!out.emplace(name, read_field(o.via.map.ptr[i].val, what + "." + printable(name))).second)
            bad(what + " repeats the field '" + printable(name) + "'");
    }
    return out;
}

std::optional<InterfaceMesh> read_mesh(const msgpack::object& o, const std::string& what) {
    if (o.type == msgpack::type::NIL) return std::nullopt;
    MapReader m(o, what);
    InterfaceMesh mesh{read_array<double>(m.need("vertices"), what + ".vertices"),
                       read_array<std::int32_t>(m.need("cells"), what + ".cells")};
    m.finish();
    if (mesh.vertices.shape.size() != 2 || mesh.vertices.shape[1] != 2) bad(what + ".vertices must have shape (n, 2)");
    if (mesh.cells.shape.size() != 2 || mesh.cells.shape[1] != 4) bad(what + ".cells must have shape (m, 4)");
    for (auto idx : mesh.cells.values)
        if (idx < 0 || static_cast<std::uint64_t>(idx) >= mesh.vertices.rows())
            bad(what + ".cells refers to vertex " + std::to_string(idx) + " of " + std::to_string(mesh.vertices.rows()));
    for (double x : mesh.vertices.values)
        if (!std::isfinite(x)) bad(what + ".vertices holds a value that is not finite");
    // Every user of the mesh assumes convex counter-clockwise cells (the fluid's inside-the-solid test, the
    // bilinear inverse map): a clockwise or twisted cell would silently contain no point at all.
    for (std::uint64_t c = 0; c < mesh.cells.rows(); ++c)
        for (int k = 0; k < 4; ++k) {
            auto corner = [&](int i) { return static_cast<std::uint64_t>(mesh.cells(c, static_cast<std::uint64_t>((k + i) % 4))); };
            const double ax = mesh.vertices(corner(0), 0), ay = mesh.vertices(corner(0), 1);
            const double bx = mesh.vertices(corner(1), 0), by = mesh.vertices(corner(1), 1);
            const double cx = mesh.vertices(corner(2), 0), cy = mesh.vertices(corner(2), 1);
            if (!((bx - ax) * (cy - by) - (by - ay) * (cx - bx) > 0.0))
                bad(what + ".cells: cell " + std::to_string(c) + " is not a convex quadrilateral with counter-clockwise corners "
                    "(it turns right or not at all at its corner " + std::to_string((k + 1) % 4) + ")");
        }
    return mesh;
}

Value read_table(const msgpack::object& o, const std::string& what) {
    if (o.type != msgpack::type::MAP) bad(what + " must be a map");
    return to_value(o, what);
}

Body read_body(MessageType type, std::uint32_t version, const msgpack::object& o) {
    const std::string w = std::string(to_string(type)) + " body";
    MapReader m(o, w);
    Body body;
    switch (type) {
        case MessageType::Hello: {
            Hello h;
            h.name = need_string(m.need("name"), w + ".name");
            h.kind = need_string(m.need("kind"), w + ".kind");
            h.version_min = need_u32(m.need("version_min"), w + ".version_min");
            h.version_max = need_u32(m.need("version_max"), w + ".version_max");
            h.software = need_string(m.need("software"), w + ".software");
            h.pid = need_int(m.need("pid"), w + ".pid");
            body = h;
            break;
        }
        case MessageType::Welcome: {
            Welcome x;
            x.version = need_u32(m.need("version"), w + ".version");
            x.heartbeat_s = need_double(m.need("heartbeat_s"), w + ".heartbeat_s");
            x.timeout_s = need_double(m.need("timeout_s"), w + ".timeout_s");
            // A NaN timeout would never expire: the participant would outlive a silent coordinator. Above 1e6 s
            // (the scene allows 60 s and 3600 s) a period overflows a clock's integer nanoseconds.
            for (double s : {x.heartbeat_s, x.timeout_s})
                if (!(s > 0.0 && s <= 1e6)) bad(w + ": heartbeat_s and timeout_s must be numbers > 0 and at most 1e6 s");
            body = x;
            break;
        }
        case MessageType::Init: {
            InitRequest r;
            r.config = read_table(m.need("config"), w + ".config");
            r.t0 = need_double(m.need("t0"), w + ".t0");
            r.interface = read_mesh(m.need("interface"), w + ".interface");
            r.state = need_bytes(m.need("state"), w + ".state");
            if (version >= 2) r.interface_state = read_fields(m.need("interface_state"), w + ".interface_state");
            body = std::move(r);
            break;
        }
        case MessageType::Ready: {
            InitReply r;
            r.dt_wanted = need_double(m.need("dt_wanted"), w + ".dt_wanted");
            r.interface = read_mesh(m.need("interface"), w + ".interface");
            r.info = read_table(m.need("info"), w + ".info");
            if (version >= 2) r.interface_state = read_fields(m.need("interface_state"), w + ".interface_state");
            body = std::move(r);
            break;
        }
        case MessageType::Advance: {
            AdvanceRequest r;
            r.t = need_double(m.need("t"), w + ".t");
            r.dt = need_double(m.need("dt"), w + ".dt");
            r.substeps = need_u32(m.need("substeps"), w + ".substeps");
            r.iteration = need_u32(m.need("iteration"), w + ".iteration");
            r.inputs = read_fields(m.need("inputs"), w + ".inputs");
            body = std::move(r);
            break;
        }
        case MessageType::Advanced: {
            AdvanceReply r;
            r.t = need_double(m.need("t"), w + ".t");
            r.dt_wanted = need_double(m.need("dt_wanted"), w + ".dt_wanted");
            r.outputs = read_fields(m.need("outputs"), w + ".outputs");
            r.substeps = need_u32(m.need("substeps"), w + ".substeps");
            r.solver_iterations = need_u32(m.need("solver_iterations"), w + ".solver_iterations");
            r.compute_s = need_double(m.need("compute_s"), w + ".compute_s");
            r.stats = read_table(m.need("stats"), w + ".stats");
            body = std::move(r);
            break;
        }
        case MessageType::Frame: {
            Frame f;
            f.t = need_double(m.need("t"), w + ".t");
            f.fields = read_fields(m.need("fields"), w + ".fields");
            body = std::move(f);
            break;
        }
        case MessageType::State: {
            State s;
            s.t = need_double(m.need("t"), w + ".t");
            s.bytes = need_bytes(m.need("state"), w + ".state");
            body = std::move(s);
            break;
        }
        case MessageType::Heartbeat:
            body = Heartbeat{need_uint(m.need("progress"), w + ".progress")};
            break;
        case MessageType::Error: {
            ErrorReply e;
            e.code = need_string(m.need("code"), w + ".code");
            e.message = need_string(m.need("message"), w + ".message");
            e.in_reply_to = need_uint(m.need("in_reply_to"), w + ".in_reply_to");
            body = std::move(e);
            break;
        }
        default:
            body = Empty{};
            break;
    }
    m.finish();
    return body;
}

constexpr std::pair<MessageType, std::string_view> kNames[] = {
    {MessageType::Hello, "HELLO"},       {MessageType::Welcome, "WELCOME"},
    {MessageType::Init, "INIT"},         {MessageType::Ready, "READY"},
    {MessageType::Advance, "ADVANCE"},   {MessageType::Advanced, "ADVANCED"},
    {MessageType::Save, "SAVE"},         {MessageType::Restore, "RESTORE"},
    {MessageType::Snapshot, "SNAPSHOT"}, {MessageType::Frame, "FRAME"},
    {MessageType::Checkpoint, "CHECKPOINT"}, {MessageType::State, "STATE"},
    {MessageType::Ack, "ACK"},           {MessageType::Heartbeat, "HEARTBEAT"},
    {MessageType::Bye, "BYE"},           {MessageType::Error, "ERROR"},
};

bool body_matches(MessageType type, const Body& body) {
    switch (type) {
        case MessageType::Hello: return std::holds_alternative<Hello>(body);
        case MessageType::Welcome: return std::holds_alternative<Welcome>(body);
        case MessageType::Init: return std::holds_alternative<InitRequest>(body);
        case MessageType::Ready: return std::holds_alternative<InitReply>(body);
        case MessageType::Advance: return std::holds_alternative<AdvanceRequest>(body);
        case MessageType::Advanced: return std::holds_alternative<AdvanceReply>(body);
        case MessageType::Frame: return std::holds_alternative<Frame>(body);
        case MessageType::State: return std::holds_alternative<State>(body);
        case MessageType::Heartbeat: return std::holds_alternative<Heartbeat>(body);
        case MessageType::Error: return std::holds_alternative<ErrorReply>(body);
        default: return std::holds_alternative<Empty>(body);
    }
}
}  // namespace

bool is_utf8(std::string_view s) {
    for (std::size_t i = 0, n; i < s.size(); i += n)
        if ((n = utf8_sequence(s, i)) == 0) return false;
    return true;
}

std::string printable(std::string_view received, std::size_t max_bytes) {
    return escaped(received, true, max_bytes);
}

std::string_view to_string(MessageType t) {
    for (const auto& [type, name] : kNames)
        if (type == t) return name;
    return "?";
}

bool parse_message_type(std::string_view name, MessageType& out) {
    for (const auto& [type, n] : kNames)
        if (n == name) return out = type, true;
    return false;
}

Message make_message(MessageType type, std::uint64_t seq, std::string token, Body body) {
    if (!body_matches(type, body)) throw std::logic_error("make_message: body does not match " + std::string(to_string(type)));
    Message m;
    m.type = type;
    m.seq = seq;
    m.token = std::move(token);
    m.body = std::move(body);
    return m;
}

void encode_value(std::string& out, const Value& v) {
    Packer pk;
    pack_value(pk, v);
    out = std::move(pk.bytes());
}

std::string encode(const Message& m) {
    if (!body_matches(m.type, m.body)) throw std::logic_error("encode: body does not match " + std::string(to_string(m.type)));
    Packer pk;
    pk.pack_map(5);
    pk.pack(std::string_view("v"));
    pk.pack_uint32(m.version);
    pk.pack(std::string_view("type"));
    pk.pack(to_string(m.type));
    pk.pack(std::string_view("seq"));
    pk.pack_uint64(m.seq);
    pk.pack(std::string_view("token"));
    pack_text(pk, m.token);
    pk.pack(std::string_view("body"));
    std::visit(BodyPacker{pk, m.version}, m.body);
    return std::move(pk.bytes());
}

namespace {

// The envelope's type as written, without reading the envelope (empty if unreadable): a HEARTBEAT or ERROR
// whose seq is missing or broken is still a message that is never answered.
std::string peek_type(const msgpack::object& envelope) {
    if (envelope.type != msgpack::type::MAP) return {};
    for (std::uint32_t i = 0; i < envelope.via.map.size; ++i) {
        const auto& kv = envelope.via.map.ptr[i];
        if (kv.key.type == msgpack::type::STR && std::string_view(kv.key.via.str.ptr, kv.key.via.str.size) == "type" &&
            kv.val.type == msgpack::type::STR)
            return std::string(kv.val.via.str.ptr, kv.val.via.str.size);
    }
    return {};
}

// The envelope's fields after seq, and the body; `type` is set as soon as it is read.
void read_envelope_rest(MapReader& env, Message& m, std::string& type) {
    type = need_string(env.need("type"), "envelope.type");
    m.version = need_u32(env.need("v"), "envelope.v");
    if (!parse_message_type(type, m.type)) throw ProtocolError("unknown_type", "unknown message type \"" + printable(type) + "\"");
    m.token = need_string(env.need("token"), "envelope.token");
    // Check the version before reading the body: another version's body may legitimately differ.
    bool hello = m.type == MessageType::Hello || m.type == MessageType::Error;
    if (!hello && (m.version < kOldestSupportedVersion || m.version > kProtocolVersion))
        throw ProtocolError("version_mismatch", "message speaks protocol version " + std::to_string(m.version) +
                                                    "; this side speaks " + std::to_string(kOldestSupportedVersion) +
                                                    " to " + std::to_string(kProtocolVersion));
    m.body = read_body(m.type, m.version, env.need("body"));
    env.finish();
}

// msgpack-c allocates an object (24 bytes) for every entry an array or map declares as soon as it reads the
// header: one 5-byte header declaring 2^20 entries cost 24 MiB, and a 64 MiB message of nested nils took
// 1.6 GB to decode. Counting what the whole message declares first bounds that: bulk data travels as bin,
// so a real message declares a few thousand entries at most.
struct DeclaredEntries : msgpack::null_visitor {
    std::size_t count = 0, limit = 0;
    bool add(std::size_t n) {
        count += n;
        return count <= limit;
    }
    bool start_array(std::uint32_t n) { return add(n); }
    bool start_map(std::uint32_t n) { return add(2 * std::size_t{n}); }
};

}  // namespace

Message decode(const void* data, std::size_t size, const DecodeLimits& limits) {
    if (size > limits.max_bytes)
        throw ProtocolError("too_large", "message of " + std::to_string(size) + " bytes exceeds the limit of " +
                                             std::to_string(limits.max_bytes));
    DeclaredEntries declared;
    declared.limit = limits.max_objects;
    std::size_t scanned = 0;
    try {
        msgpack::parse(static_cast<const char*>(data), size, scanned, declared);
    } catch (const std::exception&) {
        // a parse error: the unpack below names it
    }
    if (declared.count > limits.max_objects)
        bad("message declares more than " + std::to_string(limits.max_objects) + " array and map entries");
    msgpack::object_handle oh;
    std::size_t offset = 0;
    try {
        msgpack::unpack_limit lim(limits.max_elements, limits.max_elements, limits.max_bytes, limits.max_bytes,
                                  limits.max_bytes, limits.max_depth);
        oh = msgpack::unpack(static_cast<const char*>(data), size, offset, nullptr, nullptr, lim);
    } catch (const msgpack::insufficient_bytes&) {
        bad("message is truncated");
    } catch (const std::exception& e) {
        bad(std::string("message is not valid MessagePack: ") + e.what());
    }
    if (offset != size) bad("message has " + std::to_string(size - offset) + " trailing bytes");

    // The type is attached to every refusal it can be read from: a malformed HEARTBEAT or ERROR is not answered.
    std::optional<MapReader> env;
    Message m;
    // seq first, so that the refusal of a message whose seq is readable answers it by that seq.
    try {
        env.emplace(oh.get(), "envelope");
        m.seq = need_uint(env->need("seq"), "envelope.seq");
    } catch (const ProtocolError& e) {
        throw ProtocolError(e.code(), e.what(), 0, peek_type(oh.get()));
    }
    std::string type;
    try {
        read_envelope_rest(*env, m, type);
    } catch (const ProtocolError& e) {
        throw ProtocolError(e.code(), e.what(), m.seq, type);
    }
    return m;
}

}  // namespace sphfsi::protocol
