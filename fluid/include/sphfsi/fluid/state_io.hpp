#pragma once
// Byte-exact serialisation of solver state for checkpoints: raw little-endian copies of trivially copyable
// values and vectors (the machines that write and read a checkpoint are the same kind: x86-64/aarch64,
// both little-endian). Reading checks lengths and throws on truncation.
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace sphfsi::fluid {

class ByteWriter {
public:
    // Reserving up front also keeps GCC 12 from a false -Wstringop-overflow on the first insert.
    ByteWriter() { bytes_.reserve(4096); }
    template <class T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
        bytes_.insert(bytes_.end(), p, p + sizeof(T));
    }
    template <class T>
    void put_vector(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put<std::uint64_t>(v.size());
        if (v.empty()) return;  // data() may be null
        const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
        bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
    }
    void put_string(const std::string& s) {
        put<std::uint64_t>(s.size());
        bytes_.insert(bytes_.end(), s.begin(), s.end());
    }
    std::vector<std::uint8_t> take() { return std::move(bytes_); }

private:
    std::vector<std::uint8_t> bytes_;
};

class ByteReader {
public:
    explicit ByteReader(const std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        need(sizeof(T));
        T value;
        std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return value;
    }
    template <class T>
    void get_vector(std::vector<T>& v) {
        const auto n = get<std::uint64_t>();
        if (n > bytes_.size()) throw std::runtime_error("checkpoint: corrupt vector length");
        need(n * sizeof(T));
        v.resize(n);
        if (n) std::memcpy(static_cast<void*>(v.data()), bytes_.data() + pos_, n * sizeof(T));  // data() may be null
        pos_ += n * sizeof(T);
    }
    std::string get_string() {
        const auto n = get<std::uint64_t>();
        need(n);
        std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
        pos_ += n;
        return s;
    }
    bool at_end() const { return pos_ == bytes_.size(); }

private:
    void need(std::size_t n) const {
        if (pos_ + n > bytes_.size()) throw std::runtime_error("checkpoint: truncated state");
    }
    const std::vector<std::uint8_t>& bytes_;
    std::size_t pos_ = 0;
};

}  // namespace sphfsi::fluid
