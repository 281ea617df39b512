// Malformed input is refused with a ProtocolError carrying the right code; it never crashes.
#include <doctest/doctest.h>

#include <msgpack.hpp>
#include <cmath>
#include <random>

#include "sphfsi/protocol/codec.hpp"

using namespace sphfsi;
using namespace sphfsi::protocol;

namespace {
using Packer = msgpack::packer<msgpack::sbuffer>;

std::string code_of(const std::string& bytes, const DecodeLimits& limits = {}) {
    try {
        decode(bytes.data(), bytes.size(), limits);
    } catch (const ProtocolError& e) {
        return e.code();
    }
    return "accepted";
}

// An envelope with the given body writer and optional changes to the envelope itself.
std::string envelope(const std::function<void(Packer&)>& body, const std::string& type = "HEARTBEAT",
                     std::uint32_t v = kProtocolVersion, bool extra_key = false, std::uint64_t seq = 1) {
    msgpack::sbuffer buf;
    Packer pk(buf);
    pk.pack_map(extra_key ? 6 : 5);
    pk.pack("v");
    pk.pack(v);
    pk.pack("type");
    pk.pack(type);
    pk.pack("seq");
    pk.pack(seq);
    pk.pack("token");
    pk.pack("tok");
    pk.pack("body");
    body(pk);
    if (extra_key) {
        pk.pack("extra");
        pk.pack(1);
    }
    return std::string(buf.data(), buf.size());
}

std::string advance_with_force(std::uint64_t rows, std::size_t data_bytes, const std::string& dtype = "f8") {
    return envelope(
        [&](Packer& pk) {
            pk.pack_map(5);
            pk.pack("t"); pk.pack(0.0);
            pk.pack("dt"); pk.pack(1e-3);
            pk.pack("substeps"); pk.pack(1);
            pk.pack("iteration"); pk.pack(0);
            pk.pack("inputs");
            pk.pack_map(1);
            pk.pack("force");
            pk.pack_map(3);
            pk.pack("dtype"); pk.pack(dtype);
            pk.pack("shape"); pk.pack_array(2); pk.pack(rows); pk.pack(2);
            pk.pack("data");
            std::string zeros(data_bytes, '\0');
            pk.pack_bin(static_cast<std::uint32_t>(data_bytes));
            pk.pack_bin_body(zeros.data(), static_cast<std::uint32_t>(data_bytes));
        },
        "ADVANCE");
}
}  // namespace

TEST_CASE("well-formed hand-packed messages are accepted") {
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack(3); })) == "accepted");
    CHECK(code_of(advance_with_force(3, 48)) == "accepted");
}

TEST_CASE("every truncation of a valid message is refused as bad_message") {
    F64Array f = F64Array::zeros(5, 2);
    std::string full = encode(make_message(MessageType::Advance, 3, "tok", AdvanceRequest{0, 1, 1, 0, Fields{{"force", f}}}));
    for (std::size_t n = 0; n < full.size(); ++n) CHECK(code_of(full.substr(0, n)) == "bad_message");
    CHECK(code_of(full + "x") == "bad_message");  // trailing bytes
}

TEST_CASE("oversized messages are refused unread") {
    std::string full = encode(make_message(MessageType::Heartbeat, 1, "tok", Heartbeat{1}));
    DecodeLimits tight;
    tight.max_bytes = full.size() - 1;
    CHECK(code_of(full, tight) == "too_large");
}

TEST_CASE("wrong types, missing and unknown keys are bad_message") {
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack("three"); })) == "bad_message");
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack(-1); })) == "bad_message");
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_map(0); })) == "bad_message");  // missing key
    CHECK(code_of(envelope([](Packer& pk) {
              pk.pack_map(2); pk.pack("progress"); pk.pack(1); pk.pack("surprise"); pk.pack(2);
          })) == "bad_message");  // unknown key
    CHECK(code_of(envelope([](Packer& pk) {
              pk.pack_map(2); pk.pack("progress"); pk.pack(1); pk.pack("progress"); pk.pack(2);
          })) == "bad_message");  // repeated key
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_array(0); })) == "bad_message");  // body not a map
    CHECK(code_of(envelope([](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack(1); }, "HEARTBEAT",
                           kProtocolVersion, true)) == "bad_message");  // unknown envelope key
    msgpack::sbuffer buf;
    Packer pk(buf);
    pk.pack(std::vector<int>{1, 2, 3});  // envelope not a map
    CHECK(code_of(std::string(buf.data(), buf.size())) == "bad_message");
}

TEST_CASE("WELCOME's periods are finite, > 0 and at most 1e6 s") {
    // 1e300 s was accepted, and the participant's heartbeat thread overflowed converting it to its clock's
    // integer nanoseconds (a review, 2026-11-28); 1e6 s is far above the scene's own bounds (60 s, 3600 s).
    auto welcome = [](double heartbeat_s, double timeout_s) {
        return code_of(envelope(
            [&](Packer& pk) {
                pk.pack_map(3);
                pk.pack("version"); pk.pack(1);
                pk.pack("heartbeat_s"); pk.pack(heartbeat_s);
                pk.pack("timeout_s"); pk.pack(timeout_s);
            },
            "WELCOME"));
    };
    CHECK(welcome(0.5, 3.0) == "accepted");
    CHECK(welcome(1e6, 1e6) == "accepted");
    CHECK(welcome(1e300, 3.0) == "bad_message");
    CHECK(welcome(0.5, 1e300) == "bad_message");
    CHECK(welcome(0.0, 3.0) == "bad_message");
    CHECK(welcome(0.5, std::nan("")) == "bad_message");
}

TEST_CASE("a refusal names the offending message's seq where it could be read, else 0") {
    // docs/protocol.md, "Envelope": the ERROR answering it carries that seq and in_reply_to.
    auto seq_of = [](const std::string& bytes) {
        try {
            decode(bytes.data(), bytes.size());
        } catch (const ProtocolError& e) {
            return e.seq();
        }
        return std::uint64_t{999};
    };
    auto hb = [](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack(1); };
    const std::uint64_t seq = 77;  // unlike v (1), so that reading the wrong field shows
    CHECK(seq_of(envelope([](Packer& pk) { pk.pack_map(0); }, "HEARTBEAT", kProtocolVersion, false, seq)) == seq);
    CHECK(seq_of(envelope(hb, "DANCE", kProtocolVersion, false, seq)) == seq);
    CHECK(seq_of(envelope(hb, "HEARTBEAT", kProtocolVersion + 1, false, seq)) == seq);
    CHECK(seq_of(envelope(hb, "HEARTBEAT", kProtocolVersion, true, seq)) == seq);
    CHECK(seq_of(std::string("\xc1 not msgpack")) == 0);
    // A malformed HEARTBEAT or ERROR is not a request: the refusal says so, and nobody answers it.
    auto refusal = [](const std::string& bytes) {
        try {
            decode(bytes.data(), bytes.size());
        } catch (const ProtocolError& e) {
            return e;
        }
        FAIL("a malformed message was accepted");  // (an empty stand-in would read as answerable)
        return ProtocolError("none", "accepted", 0, "");
    };
    const auto bad_heartbeat = refusal(envelope([](Packer& pk) { pk.pack_map(0); }, "HEARTBEAT", kProtocolVersion, false, seq));
    CHECK(bad_heartbeat.type_name() == "HEARTBEAT");
    CHECK_FALSE(bad_heartbeat.answerable());
    CHECK_FALSE(refusal(envelope([](Packer& pk) { pk.pack_map(0); }, "ERROR", kProtocolVersion, false, seq)).answerable());
    CHECK(refusal(envelope([](Packer& pk) { pk.pack_map(0); }, "ADVANCE", kProtocolVersion, false, seq)).answerable());
    CHECK(refusal(std::string("\xc1 not msgpack")).answerable());
    msgpack::sbuffer buf;
    Packer pk(buf);
    pk.pack_map(1);
    pk.pack("seq");
    pk.pack("seven");  // a seq that is not a number cannot be answered by
    CHECK(seq_of(std::string(buf.data(), buf.size())) == 0);
    // Nor is a HEARTBEAT or ERROR without a readable seq answered (its type says what it is); a request
    // without one is, by seq 0.
    for (const char* type : {"HEARTBEAT", "ERROR", "ADVANCE"}) {
        msgpack::sbuffer b;
        Packer p(b);
        p.pack_map(2);
        p.pack("type");
        p.pack(type);
        p.pack("seq");
        p.pack("seven");
        const auto e = refusal(std::string(b.data(), b.size()));
        CHECK(e.seq() == 0);
        CHECK(e.answerable() == (std::string(type) == "ADVANCE"));
    }
    // Nor when the envelope has a key that is not a string (found by a review: the envelope's own check ran
    // before the type was read, and the refusal was answered).
    for (const char* type : {"HEARTBEAT", "ADVANCE"}) {
        msgpack::sbuffer b;
        Packer p(b);
        p.pack_map(2);
        p.pack("type");
        p.pack(type);
        p.pack(7);
        p.pack(1);
        const auto e = refusal(std::string(b.data(), b.size()));
        CHECK(e.code() == "bad_message");
        CHECK(e.answerable() == (std::string(type) == "ADVANCE"));
    }
}

TEST_CASE("arrays whose bytes do not match their shape or dtype are refused") {
    CHECK(code_of(advance_with_force(3, 47)) == "bad_message");
    CHECK(code_of(advance_with_force(3, 49)) == "bad_message");
    CHECK(code_of(advance_with_force(3, 24, "i4")) == "accepted");
    CHECK(code_of(advance_with_force(3, 48, "f4")) == "bad_message");
    CHECK(code_of(advance_with_force(std::uint64_t{1} << 62, 0)) == "bad_message");  // overflowing shape
}

TEST_CASE("unknown type and unknown version are refused with their own codes") {
    auto hb = [](Packer& pk) { pk.pack_map(1); pk.pack("progress"); pk.pack(1); };
    CHECK(code_of(envelope(hb, "DANCE")) == "unknown_type");
    CHECK(code_of(envelope(hb, "HEARTBEAT", kProtocolVersion + 1)) == "version_mismatch");
    CHECK(code_of(envelope(hb, "HEARTBEAT", 0)) == "version_mismatch");
}

TEST_CASE("a message declaring more entries than the limit is refused before they are allocated") {
    // Each declared entry costs msgpack-c a 24-byte object as soon as its array's header is read: 5 bytes
    // declaring 2^20 nils, or nested arrays of nils, made a small message a large allocation.
    msgpack::sbuffer buf;
    Packer pk(buf);
    pk.pack_map(1);
    pk.pack("seq");
    pk.pack_array(std::uint32_t{1} << 20);
    DecodeLimits limits;
    const std::string header(buf.data(), buf.size());
    try {
        decode(header.data(), header.size(), limits);
        FAIL("accepted");
    } catch (const ProtocolError& e) {
        CHECK(std::string(e.what()).find("declares more than") != std::string::npos);  // not "truncated"
    }
    msgpack::sbuffer nested;
    Packer np(nested);
    np.pack_array(16);
    for (int i = 0; i < 16; ++i) {
        np.pack_array(100000);
        for (int k = 0; k < 100000; ++k) np.pack_nil();
    }
    const std::string many(nested.data(), nested.size());
    try {
        decode(many.data(), many.size(), limits);
        FAIL("accepted");
    } catch (const ProtocolError& e) {
        CHECK(std::string(e.what()).find("declares more than") != std::string::npos);
    }
    limits.max_objects = 2000000;  // the same message under a looser bound is read, and refused as no envelope
    try {
        decode(many.data(), many.size(), limits);
        FAIL("accepted");
    } catch (const ProtocolError& e) {
        CHECK(std::string(e.what()).find("envelope") != std::string::npos);
    }
}

TEST_CASE("deep nesting is refused, not a stack overflow") {
    msgpack::sbuffer buf;
    Packer pk(buf);
    for (int i = 0; i < 100000; ++i) pk.pack_array(1);
    pk.pack(1);
    CHECK(code_of(std::string(buf.data(), buf.size())) == "bad_message");
}

TEST_CASE("random bytes and random corruptions never crash the decoder") {
    std::mt19937 rng(12345);  // fixed seed: the test is repeatable
    std::string valid = encode(make_message(MessageType::Advance, 3, "tok",
                                            AdvanceRequest{0, 1, 1, 0, Fields{{"force", F64Array::zeros(4, 2)}}}));
    int refused = 0;
    for (int i = 0; i < 20000; ++i) {
        std::string bytes = valid;
        if (i % 2) {
            bytes.resize(rng() % 64);
            for (auto& c : bytes) c = static_cast<char>(rng());
        } else {
            for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng());
        }
        std::string code = code_of(bytes);
        refused += code != "accepted";
        if (code == "accepted") {  // what is accepted is a valid message: it re-encodes and decodes the same
            const Message m = decode(bytes.data(), bytes.size());
            const std::string again = encode(m);
            CHECK(encode(decode(again.data(), again.size())) == again);
        }
    }
    CHECK(refused > 10000);  // nearly everything random is refused
    CHECK(refused < 20000);  // and the corruptions that hit only the data leave messages that decode
}

TEST_CASE("interface meshes with cells that are not convex and counter-clockwise are refused") {
    // Two unit squares side by side: vertices 0-1-2 along y = 0, 3-4-5 along y = 1.
    auto ready = [](std::vector<std::int32_t> cells, double x0 = 0.0) {
        InitReply r;
        r.dt_wanted = 1e-3;
        r.info = Value(Value::Table{});
        const std::uint64_t rows = cells.size() / 4;
        r.interface = InterfaceMesh{F64Array({6, 2}, {x0, 0, 1, 0, 2, 0, 0, 1, 1, 1, 2, 1}), I32Array({rows, 4}, std::move(cells))};
        const std::string bytes = encode(make_message(MessageType::Ready, 3, "tok", std::move(r)));
        try {
            decode(bytes.data(), bytes.size());
        } catch (const ProtocolError& e) {
            return std::string(e.code()) + ": " + e.what();
        }
        return std::string("accepted");
    };
    CHECK(ready({0, 1, 4, 3, 1, 2, 5, 4}) == "accepted");
    CHECK(ready({4, 3, 0, 1, 1, 2, 5, 4}) == "accepted");  // any corner may come first
    // Clockwise: the fluid's inside test would find no point in it, silently.
    CHECK(ready({0, 1, 4, 3, 1, 4, 5, 2}).find("bad_message: READY body.interface.cells: cell 1 is not a convex") == 0);
    CHECK(ready({0, 1, 3, 4}).find("bad_message") == 0);        // twisted (a bow tie)
    CHECK(ready({0, 1, 2, 4}).find("bad_message") == 0);        // three corners in a line: no area there
    CHECK(ready({0, 1, 4, 3}, std::nan("")).find("bad_message: READY body.interface.vertices holds a value that is not finite") == 0);
}
