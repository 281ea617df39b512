#pragma once
// MessagePack encoding and strict decoding of protocol messages. Decoding never trusts its input:
// every type, size and key is checked, and any violation is a ProtocolError, never a crash.
#include <cstddef>
#include <string>

#include "sphfsi/protocol/message.hpp"

namespace sphfsi::protocol {

struct DecodeLimits {
    std::size_t max_bytes = std::size_t{1} << 30;  // whole message; larger is refused unread
    std::size_t max_depth = 32;                    // nesting of maps/arrays
    std::size_t max_elements = 1u << 20;           // entries of one msgpack array or map
};

std::string encode(const Message& m);
Message decode(const void* data, std::size_t size, const DecodeLimits& limits = {});

// Value <-> msgpack (config trees travel inside INIT and READY).
void encode_value(std::string& out, const Value& v);

}  // namespace sphfsi::protocol
