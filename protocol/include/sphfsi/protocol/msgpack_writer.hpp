#pragma once
// A msgpack packer that always writes floats as float64. msgpack-cxx 4's pack_double() writes
// integral-valued doubles as integers (and -0.0 as 0), which would change a value's type on the wire.
#include <bit>
#include <cstdint>
#include <cstring>
#include <msgpack.hpp>
#include <string>

namespace sphfsi::protocol {

struct ByteSink {
    std::string bytes;
    void write(const char* p, std::size_t n) { bytes.append(p, n); }
};

class Writer : public msgpack::packer<ByteSink> {
public:
    Writer() : msgpack::packer<ByteSink>(sink_) {}
    Writer& f64(double d) {
        std::uint64_t bits;
        std::memcpy(&bits, &d, 8);
        char b[9];
        b[0] = static_cast<char>(0xcb);
        for (int i = 0; i < 8; ++i) b[1 + i] = static_cast<char>(bits >> (56 - 8 * i));
        sink_.write(b, 9);
        return *this;
    }
    Writer& bin(const void* data, std::size_t size) {
        pack_bin(static_cast<std::uint32_t>(size));
        pack_bin_body(static_cast<const char*>(data), static_cast<std::uint32_t>(size));
        return *this;
    }
    std::string& bytes() { return sink_.bytes; }

private:
    ByteSink sink_;
};

}  // namespace sphfsi::protocol
