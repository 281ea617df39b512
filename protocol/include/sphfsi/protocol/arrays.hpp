#pragma once
// Bulk data on the wire: row-major arrays with a shape, sent as little-endian binary blobs.
#include <cstdint>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace sphfsi::protocol {

template <class T>
struct NdArray {
    std::vector<std::uint64_t> shape;  // e.g. {n, 2} for n 2-vectors
    using value_type = T;
    std::vector<T> values;             // row-major, size == product(shape)

    NdArray() = default;
    NdArray(std::vector<std::uint64_t> s, std::vector<T> v) : shape(std::move(s)), values(std::move(v)) {}
    static NdArray zeros(std::uint64_t rows, std::uint64_t cols) {
        return NdArray({rows, cols}, std::vector<T>(rows * cols, T{}));
    }
    std::uint64_t rows() const { return shape.empty() ? 0 : shape[0]; }
    std::uint64_t cols() const { return shape.size() < 2 ? 1 : shape[1]; }
    T& operator()(std::uint64_t r, std::uint64_t c) { return values[r * cols() + c]; }
    const T& operator()(std::uint64_t r, std::uint64_t c) const { return values[r * cols() + c]; }
    bool operator==(const NdArray&) const = default;
};

using F64Array = NdArray<double>;        // dtype "f8"
using I32Array = NdArray<std::int32_t>;  // dtype "i4"
using Field = std::variant<F64Array, I32Array>;
using Fields = std::map<std::string, Field, std::less<>>;

// Interface mesh published by the structure: solid cross-section as quadrilateral cells.
struct InterfaceMesh {
    F64Array vertices;  // (n, 2) reference positions [m]
    I32Array cells;     // (m, 4) vertex indices, counter-clockwise
    bool operator==(const InterfaceMesh&) const = default;
};

}  // namespace sphfsi::protocol
