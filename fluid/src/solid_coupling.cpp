#include "sphfsi/fluid/solid_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sphfsi::fluid {
namespace {

Vec2 row(const protocol::F64Array& a, std::size_t i) { return Vec2{{a(i, 0), a(i, 1)}}; }

// Shape and values: a NaN at a dry vertex would put solid particles in no grid cell, silently, and travel
// on into the next window, the record and the checkpoint.
void check_shape(const protocol::F64Array& a, std::size_t n, const char* name) {
    if (a.shape.size() != 2 || a.rows() != n || a.cols() != 2)
        throw std::invalid_argument(std::string("interface input '") + name + "' must have shape (" + std::to_string(n) +
                                    ", 2), got " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()));
    for (std::size_t k = 0; k < a.values.size(); ++k)
        if (!std::isfinite(a.values[k]))
            throw std::invalid_argument(std::string("interface input '") + name + "' at vertex " + std::to_string(k / 2) +
                                        " is not a finite number");
}

}  // namespace

InterfaceCoupling::InterfaceCoupling(const protocol::InterfaceMesh& mesh, double dp) {
    const auto& V = mesh.vertices;
    const auto& C = mesh.cells;
    if (V.shape.size() != 2 || V.cols() != 2) throw std::invalid_argument("interface mesh: vertices must be (n, 2)");
    if (C.shape.size() != 2 || C.cols() != 4) throw std::invalid_argument("interface mesh: cells must be (m, 4)");
    const std::size_t nv = V.rows();
    for (std::size_t i = 0; i < nv; ++i) reference_.push_back(row(V, i));
    for (std::size_t c = 0; c < C.rows(); ++c) {
        std::array<Vec2, 4> X;
        std::array<std::int32_t, 4> ids;
        for (int k = 0; k < 4; ++k) {
            ids[k] = C(c, static_cast<std::uint64_t>(k));
            if (ids[k] < 0 || static_cast<std::size_t>(ids[k]) >= nv)
                throw std::invalid_argument("interface mesh: cell " + std::to_string(c) + " names vertex " +
                                            std::to_string(ids[k]) + " of " + std::to_string(nv));
            X[k] = reference_[static_cast<std::size_t>(ids[k])];
        }
        // Particles per parametric direction: the longer of the two opposite edges over dp, at least one.
        const double len_xi = std::max(norm(X[1] - X[0]), norm(X[2] - X[3]));
        const double len_eta = std::max(norm(X[3] - X[0]), norm(X[2] - X[1]));
        const int n_xi = std::max(1, static_cast<int>(std::lround(len_xi / dp)));
        const int n_eta = std::max(1, static_cast<int>(std::lround(len_eta / dp)));
        for (int b = 0; b < n_eta; ++b)
            for (int a = 0; a < n_xi; ++a) {
                const double xi = (a + 0.5) / n_xi, eta = (b + 0.5) / n_eta;
                SolidParticleWeights w;
                w.vertex = ids;
                w.weight = {(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta};
                Vec2 x{};
                for (int k = 0; k < 4; ++k) x += X[k] * w.weight[k];
                weights_.push_back(w);
                particles_ref_.push_back(x);
            }
    }
    state_.u0.assign(nv, Vec2{});
    state_.v0.assign(nv, Vec2{});
    state_.u1 = state_.u0;
    state_.v1 = state_.v0;
}

std::vector<Vec2> InterfaceCoupling::displaced_positions(const std::vector<double>& displacement) const {
    std::vector<Vec2> x = particles_ref_;
    if (displacement.empty()) return x;
    for (std::size_t k = 0; k < x.size(); ++k)
        for (int q = 0; q < 4; ++q) {
            const auto v = static_cast<std::size_t>(weights_[k].vertex[static_cast<std::size_t>(q)]);
            x[k] += Vec2{{displacement[2 * v], displacement[2 * v + 1]}} * weights_[k].weight[static_cast<std::size_t>(q)];
        }
    return x;
}

void InterfaceCoupling::begin_window(double t0, double dt, const protocol::F64Array* displacement,
                                     const protocol::F64Array* velocity) {
    const std::size_t n = reference_.size();
    // Both shapes first: a refused window (bad_message) must change nothing (docs/protocol.md §3), and a
    // CHECKPOINT after it once stored the half-started window.
    if (displacement) check_shape(*displacement, n, "displacement");
    if (velocity) check_shape(*velocity, n, "velocity");
    state_.t0 = t0;
    state_.dt = dt;
    state_.u1 = state_.u0;
    state_.v1 = state_.v0;
    if (displacement)
        for (std::size_t i = 0; i < n; ++i) state_.u1[i] = row(*displacement, i);
    if (velocity)
        for (std::size_t i = 0; i < n; ++i) state_.v1[i] = row(*velocity, i);
}

void InterfaceCoupling::end_window() {
    state_.u0 = state_.u1;
    state_.v0 = state_.v1;
    state_.t0 += state_.dt;
    state_.dt = 0.0;
}

InterfaceCoupling::WindowPoint InterfaceCoupling::window_point(double t) const {
    // Fraction of the window elapsed; outside a window (dt = 0) the structure sits at its start values.
    // The window's end is the time the fluid advances to, t0 + dt, compared as such: (t - t0)/dt rounds to
    // just under 1 there about every other window, and the solids then ended a hair short of u1, which the
    // next window's start (u0 = u1) did not match, so the fluid re-evaluated everything (a full evaluation
    // in half of all windows, 20 % of a thesis-window run's fluid time at dp = 2 mm).
    return {state_.dt > 0.0 ? std::clamp((t - state_.t0) / state_.dt, 0.0, 1.0) : 0.0,
            state_.dt > 0.0 && t >= state_.t0 + state_.dt};
}

// At the window's end the end values themselves (u0 + (u1 - u0) need not round to u1): a window's end and the
// next window's start then put the solid particles at bitwise the same place, which lets the fluid keep the
// rates of its end-of-window evaluation and only redo the part that depends on the new window's
// acceleration (Simulation2D::refresh_solid_rates).
Vec2 InterfaceCoupling::vertex_displacement(std::size_t i, WindowPoint p) const {
    return p.end ? state_.u1[i] : state_.u0[i] + (state_.u1[i] - state_.u0[i]) * p.s;
}

void InterfaceCoupling::vertex_positions(double t, std::vector<Vec2>& out) const {
    const WindowPoint p = window_point(t);
    out.resize(reference_.size());
    for (std::size_t i = 0; i < reference_.size(); ++i) out[i] = reference_[i] + vertex_displacement(i, p);
}

void InterfaceCoupling::kinematics(std::size_t k, double t, Vec2& x, Vec2& v, Vec2& a) const {
    const auto& w = weights_[k];
    const WindowPoint p = window_point(t);
    const double s = p.s;
    const double inv_dt = state_.dt > 0.0 ? 1.0 / state_.dt : 0.0;
    x = particles_ref_[k];
    v = Vec2{};
    a = Vec2{};
    for (int q = 0; q < 4; ++q) {
        const std::size_t i = static_cast<std::size_t>(w.vertex[q]);
        const Vec2 vel = p.end ? state_.v1[i] : state_.v0[i] + (state_.v1[i] - state_.v0[i]) * s;  // as the displacement
        x += vertex_displacement(i, p) * w.weight[q];
        v += vel * w.weight[q];
        a += (state_.v1[i] - state_.v0[i]) * (inv_dt * w.weight[q]);
    }
}

protocol::F64Array InterfaceCoupling::map_forces(const std::vector<SolidParticleWeights>& weights,
                                                 const std::vector<Vec2>& particle_forces, std::size_t n_vertices) {
    auto out = protocol::F64Array::zeros(n_vertices, 2);
    for (std::size_t p = 0; p < weights.size(); ++p)
        for (int q = 0; q < 4; ++q) {
            const auto v = static_cast<std::uint64_t>(weights[p].vertex[q]);
            out(v, 0) += weights[p].weight[q] * particle_forces[p][0];
            out(v, 1) += weights[p].weight[q] * particle_forces[p][1];
        }
    return out;
}

}  // namespace sphfsi::fluid
