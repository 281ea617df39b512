#pragma once
// Interface mapping between the structure's interface mesh (quad cells) and points inside it
// (fluid boundary particles, watchpoints). A point carries bilinear weights on its cell's four
// vertices: kinematics are interpolated with them (consistent) and point forces are spread back
// with the same weights (conservative). Because the weights sum to one and reproduce linear fields,
// total force and total moment are preserved exactly (docs/protocol.md section 2.2).
#include <array>
#include <cstdint>

#include "sphfsi/protocol/arrays.hpp"

namespace sphfsi::protocol {

struct MappedPoint {
    std::int32_t cell = -1;
    std::array<std::int32_t, 4> vertex{};  // the cell's vertex indices
    std::array<double, 4> weight{};        // bilinear weights, summing to 1
    double distance = 0.0;                 // 0 inside the cell, else the distance to it [m]
};

// Bilinear weights of (x, y) in the quad (p0, p1, p2, p3) (counter-clockwise), found by Newton on the
// reference coordinates; (xi, eta) are clamped to the cell when the point lies outside it.
std::array<double, 4> bilinear_weights(const std::array<std::array<double, 2>, 4>& quad, double x, double y,
                                       double* outside_distance = nullptr);

// The cell containing (x, y) in the reference configuration, or the nearest one.
MappedPoint locate(const InterfaceMesh& mesh, double x, double y);

// Value at a mapped point of a vertex field (n, 2).
std::array<double, 2> interpolate(const MappedPoint& p, const F64Array& vertex_field);

// Adds a point force to vertex forces (n, 2) with the transposed weights.
void spread(const MappedPoint& p, const std::array<double, 2>& force, F64Array& vertex_forces);

}  // namespace sphfsi::protocol
