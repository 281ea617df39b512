#pragma once
// The coupled structure's cross-section as the fluid's failure check sees it: the interface mesh's quad
// cells at their current place. A fluid particle centre deeper inside it than its solid particles' layers
// reach from a face the water touches (an edge no other cell shares) has gone through the structure's wall,
// as one beyond a tank wall's outer face has gone through that; across a section thinner than two of those
// layers, that is within half a spacing of its middle and at least half a spacing past the face (the rule
// of the static obstacles, Simulation2D::through_obstacle). Measured in the coupled scenes at their
// defaults (elastic gate at 1 and 4 mm, elastic obstacle at 4 mm, hydrostatic plate): no fluid centre ever
// inside a cross-section; the gate at 3 mm without the repulsive force put one at its middle at t = 0.38 s.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

class SolidSection {
public:
    using Vertices = std::function<void(double t, std::vector<Vec2>& out)>;  // the mesh's vertices at time t

    SolidSection() = default;
    // `cells`: counter-clockwise quads of vertex indices; `layers`: how deep the solid particles reach from a
    // face (the tank's wall thickness); `dp`: the particle spacing.
    SolidSection(std::vector<std::array<std::int32_t, 4>> cells, Vertices vertices, double layers, double dp);

    bool on() const { return static_cast<bool>(vertices_); }
    // Moves the cells to time t; then lost() answers for positions at that time.
    void place(double t);
    // Whether a fluid centre at x is inside the section deeper than the rule allows.
    bool lost(const Vec2& x) const;

private:
    std::vector<std::array<std::int32_t, 4>> cells_;
    std::vector<std::array<bool, 4>> face_;  // edge k (vertex k to k+1) is a face the water touches
    Vertices vertices_;
    double layers_ = 0.0, dp_ = 0.0;
    std::vector<Vec2> at_;                   // vertices at the placed time
    Vec2 lo_{}, hi_{};                       // their bounding box
};

}  // namespace sphfsi::fluid
