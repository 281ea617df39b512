// Text the codec writes is UTF-8 (docs/protocol.md, "Envelope": strings are UTF-8 msgpack str), also when an
// error quotes bytes a peer sent that are not: the participants and the coordinator answer a message whose
// `type` is not UTF-8 with ERROR unknown_type quoting that type, and a strict reader (msgpack-python with
// raw=False) cannot decode an ERROR whose message is not UTF-8.
#include <doctest/doctest.h>

#include <msgpack.hpp>

#include "sphfsi/protocol/codec.hpp"

using namespace sphfsi;
using namespace sphfsi::protocol;

namespace {
// Independent of the codec's own check: decode code points and test their ranges.
bool utf8(const std::string& s) {
    for (std::size_t i = 0; i < s.size();) {
        const auto c = static_cast<unsigned char>(s[i]);
        const std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
        if (n == 0 || i + n > s.size()) return false;
        std::uint32_t cp = n == 1 ? c : c & (0x7F >> n);
        for (std::size_t k = 1; k < n; ++k) {
            const auto b = static_cast<unsigned char>(s[i + k]);
            if ((b & 0xC0) != 0x80) return false;
            cp = (cp << 6) | (b & 0x3F);
        }
        const std::uint32_t least[] = {0, 0, 0x80, 0x800, 0x10000};
        if (cp < least[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
        i += n;
    }
    return true;
}

ProtocolError refusal(const std::string& bytes) {
    try {
        decode(bytes.data(), bytes.size());
    } catch (const ProtocolError& e) {
        return e;
    }
    FAIL("accepted");
    return ProtocolError("none", "accepted");
}

// A HEARTBEAT envelope with the given type and an optional extra body key, both as raw bytes.
std::string envelope(const std::string& type, const std::string& extra_key = "") {
    msgpack::sbuffer buf;
    msgpack::packer<msgpack::sbuffer> pk(buf);
    pk.pack_map(5);
    pk.pack("v"); pk.pack(1);
    pk.pack("type"); pk.pack(type);  // msgpack-c writes the bytes as they are
    pk.pack("seq"); pk.pack(5);
    pk.pack("token"); pk.pack("tok");
    pk.pack("body");
    pk.pack_map(extra_key.empty() ? 1 : 2);
    pk.pack("progress"); pk.pack(1);
    if (!extra_key.empty()) {
        pk.pack(extra_key);
        pk.pack(1);
    }
    return std::string(buf.data(), buf.size());
}

// The text of the ERROR message `m` as it arrives on the other side.
std::string sent_text(const std::string& message) {
    const std::string bytes = encode(make_message(MessageType::Error, 3, "tok", ErrorReply{"bad_message", message, 3}));
    return decode(bytes.data(), bytes.size()).as<ErrorReply>().message;
}
}  // namespace

TEST_CASE("printable escapes bytes outside UTF-8 and control characters, keeps the rest") {
    CHECK(printable("HEARTBEAT") == "HEARTBEAT");
    CHECK(printable("d\xc3\xa9j\xc3\xa0 \xe2\x82\xac \xf0\x9f\x98\x80") == "d\xc3\xa9j\xc3\xa0 \xe2\x82\xac \xf0\x9f\x98\x80");
    CHECK(printable(std::string("\xff\xfe\x1b[2J\n\0x", 9)) == "\\xff\\xfe\\x1b[2J\\x0a\\x00x");
    CHECK(printable("\xc0\xaf") == "\\xc0\\xaf");                  // overlong '/'
    CHECK(printable("\xed\xa0\x80") == "\\xed\\xa0\\x80");          // a surrogate
    CHECK(printable("\xf4\x90\x80\x80") == "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
    CHECK(printable("ab\xe2\x82") == "ab\\xe2\\x82");               // truncated sequence
    // Bidirectional overrides and isolates would reorder the rest of a log line as it is displayed.
    CHECK(printable("a\xe2\x80\xae" "b") == "a\\xe2\\x80\\xae" "b");      // U+202E RIGHT-TO-LEFT OVERRIDE
    CHECK(printable("a\xe2\x81\xa6" "b") == "a\\xe2\\x81\\xa6" "b");      // U+2066 LEFT-TO-RIGHT ISOLATE
    CHECK(printable("\xe2\x80\x94") == "\xe2\x80\x94");              // an em dash stays
    // Long input is cut, never inside a character.
    CHECK(printable(std::string(200, 'a')) == std::string(80, 'a') + "...");
    CHECK(printable("\xc3\xa9\xc3\xa9\xc3\xa9", 3) == "\xc3\xa9\xc3\xa9...");
    CHECK(utf8(printable(std::string("\xe2\x82\xac\xff", 4), 1)));
}

TEST_CASE("a refusal quoting a type or key that is not UTF-8 is UTF-8") {
    const ProtocolError type = refusal(envelope("\xff\xfe\x1bX"));
    CHECK(type.code() == "unknown_type");
    CHECK(utf8(type.what()));
    CHECK(std::string(type.what()).find("\\xff\\xfe\\x1bX") != std::string::npos);
    CHECK(utf8(sent_text(type.what())));

    const ProtocolError key = refusal(envelope("HEARTBEAT", "col\xc0our"));
    CHECK(key.code() == "bad_message");
    CHECK(utf8(key.what()));
    CHECK(std::string(key.what()).find("col\\xc0our") != std::string::npos);
}

TEST_CASE("the encoder writes only UTF-8, and valid text unchanged") {
    // Whatever a caller puts in (here a text built from a peer's bytes without printable()), the str on the
    // wire is UTF-8: the invalid bytes are escaped.
    CHECK(sent_text("unknown key '\xff\xfe'") == "unknown key '\\xff\\xfe'");
    CHECK(utf8(sent_text(std::string("\xed\xa0\x80\xc0\xaf\xf8", 6))));
    const std::string text = "d\xc3\xa9j\xc3\xa0 \xe2\x82\xac\n\ttab \xf0\x9f\x98\x80 \x1b";
    CHECK(sent_text(text) == text);  // control characters are valid UTF-8: only printable() escapes them

    Value::Table config{{"na\xffme", Value("va\xfelue")}};
    Message init = make_message(MessageType::Init, 2, "tok", InitRequest{Value(config), 0.0, std::nullopt, {}, {}});
    const std::string bytes = encode(init);
    const Value got = decode(bytes.data(), bytes.size()).as<InitRequest>().config;
    CHECK(got.at("na\\xffme").as_string() == "va\\xfelue");
}
