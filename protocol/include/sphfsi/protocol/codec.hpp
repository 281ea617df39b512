#pragma once
// MessagePack encoding and strict decoding of protocol messages. Decoding never trusts its input:
// every type, size and key is checked, and any violation is a ProtocolError, never a crash.
#include <cstddef>
#include <string>
#include <string_view>

#include "sphfsi/protocol/message.hpp"

namespace sphfsi::protocol {

struct DecodeLimits {
    std::size_t max_bytes = std::size_t{1} << 30;  // whole message; larger is refused unread
    std::size_t max_depth = 32;                    // nesting of maps/arrays
    std::size_t max_elements = 1u << 20;           // entries of one msgpack array or map
    std::size_t max_objects = 1u << 20;            // entries of all arrays and maps together
};

std::string encode(const Message& m);
Message decode(const void* data, std::size_t size, const DecodeLimits& limits = {});

// Value <-> msgpack (config trees travel inside INIT and READY).
void encode_value(std::string& out, const Value& v);

// A string received from a peer, made fit to quote in an error text or a log line: every byte that is not
// part of valid UTF-8, and every ASCII control character, becomes `\xNN`; beyond `max_bytes` of input the
// rest is cut and "..." appended. An error text goes back in ERROR `message`, a msgpack str, which must be
// UTF-8 (docs/protocol.md, "Envelope"): quoting the received bytes as they are would make our own reply
// malformed. Use it wherever a received string (a type, key, dtype or field name) goes into a text.
std::string printable(std::string_view received, std::size_t max_bytes = 80);

// Whether `s` is well-formed UTF-8 (RFC 3629; what a strict decoder such as Python's accepts).
bool is_utf8(std::string_view s);

}  // namespace sphfsi::protocol
