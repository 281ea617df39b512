#pragma once
// Solid particles driven by the structure's interface mesh (docs/protocol.md, section 2.2). At set-up every
// quadrilateral cell (reference configuration) is filled with particles at about the fluid spacing, at
// cell-centred parametric points (xi, eta) so neighbouring cells never duplicate a particle on their shared
// edge; each particle keeps its bilinear weights on the cell's four vertices. Positions and velocities
// follow the vertices by the same weights, linearly in time across a coupling window. Forces go back with
// the transposed weights, F_v = sum_p w_pv f_p: since the weights of a particle sum to one and reproduce
// its position (x_p = sum_v w_pv x_v), total force and moment are preserved exactly.
#include <array>
#include <cstdint>
#include <vector>

#include "sphfsi/fluid/vec.hpp"
#include "sphfsi/protocol/arrays.hpp"

namespace sphfsi::fluid {

struct SolidParticleWeights {
    std::array<std::int32_t, 4> vertex{};
    std::array<double, 4> weight{};
};

class InterfaceCoupling {
public:
    InterfaceCoupling() = default;
    // Throws std::invalid_argument naming the problem when the mesh is malformed.
    InterfaceCoupling(const protocol::InterfaceMesh& mesh, double dp);

    std::size_t particle_count() const { return weights_.size(); }
    std::size_t vertex_count() const { return reference_.size(); }
    const std::vector<Vec2>& reference_positions() const { return particles_ref_; }
    const std::vector<Vec2>& vertex_reference() const { return reference_; }
    const std::vector<SolidParticleWeights>& weights() const { return weights_; }
    // The particles' positions with the vertices displaced by `displacement` (2 values per vertex, as a
    // checkpoint keeps it; empty: the reference positions).
    std::vector<Vec2> displaced_positions(const std::vector<double>& displacement) const;

    // Starts a window [t0, t0 + dt] whose end values are `displacement` / `velocity` ((n, 2) each; a null
    // pointer keeps the window-start values: the structure stands still).
    void begin_window(double t0, double dt, const protocol::F64Array* displacement, const protocol::F64Array* velocity);
    // The window's end values become the next window's start values.
    void end_window();

    // Position, velocity and acceleration of solid particle k at time t (inside the current window).
    void kinematics(std::size_t k, double t, Vec2& x, Vec2& v, Vec2& a) const;
    // The vertices' positions at time t, where kinematics() puts the particles' cells.
    void vertex_positions(double t, std::vector<Vec2>& out) const;

    // F_v = sum_p w_pv f_p, shape (n_vertices, 2).
    static protocol::F64Array map_forces(const std::vector<SolidParticleWeights>& weights,
                                         const std::vector<Vec2>& particle_forces, std::size_t n_vertices);

    // Window state for save/restore and checkpoints.
    struct State {
        std::vector<Vec2> u0, v0, u1, v1;
        double t0 = 0.0, dt = 0.0;
    };
    const State& state() const { return state_; }
    void set_state(const State& s) { state_ = s; }

private:
    // Where time t falls in the current window: the fraction elapsed, and whether it is the window's end.
    struct WindowPoint {
        double s;
        bool end;
    };
    WindowPoint window_point(double t) const;
    Vec2 vertex_displacement(std::size_t i, WindowPoint p) const;  // vertex i's, at that point

    std::vector<Vec2> reference_;       // vertex reference positions
    std::vector<Vec2> particles_ref_;   // particle reference positions
    std::vector<SolidParticleWeights> weights_;
    State state_;
};

}  // namespace sphfsi::fluid
