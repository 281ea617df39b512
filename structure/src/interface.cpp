#include "sphfsi/structure/interface.hpp"

#include <cmath>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {

using protocol::F64Array;
using protocol::SolverError;

InterfaceMap::InterfaceMap(const Model& model, const StructureConfig& config) : model_(&model) {
    const double half = 0.5 * config.section.thickness;
    std::vector<std::int32_t> cells;
    for (std::size_t m = 0; m < config.members.size(); ++m) {
        if (!config.members[m].wetted) continue;
        const auto& nodes = model.member_nodes[m];
        const Vec2 axis = (model.nodes[nodes.back()] - model.nodes[nodes.front()]).normalized();
        const Vec2 normal(-axis.y(), axis.x());
        const auto first = static_cast<std::int32_t>(vertices_.size());
        const double right = half + config.members[m].pad_right, left = half + config.members[m].pad_left;
        for (int node : nodes) {
            vertices_.push_back({node, -right * normal});  // bottom (right) face: index first + 2k
            vertices_.push_back({node, left * normal});    // top (left) face: first + 2k + 1
        }
        for (std::int32_t k = 0; k + 1 < static_cast<std::int32_t>(nodes.size()); ++k) {
            const std::int32_t b0 = first + 2 * k, b1 = b0 + 2;
            cells.insert(cells.end(), {b0, b1, b1 + 1, b0 + 1});
        }
    }
    mesh_.vertices = F64Array::zeros(vertices_.size(), 2);
    for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const Vec2 x = model.nodes[vertices_[i].node] + vertices_[i].offset;
        mesh_.vertices(i, 0) = x.x();
        mesh_.vertices(i, 1) = x.y();
    }
    const std::uint64_t quads = cells.size() / 4;  // before the move: argument order is unspecified
    mesh_.cells = protocol::I32Array({quads, 4}, std::move(cells));
}

Vec2 InterfaceMap::arm(const Vertex& vx, const Vector& u) const {
    const double th = u[3 * vx.node + 2], c = std::cos(th), s = std::sin(th);
    return {c * vx.offset.x() - s * vx.offset.y(), s * vx.offset.x() + c * vx.offset.y()};
}

F64Array InterfaceMap::displacement(const Vector& u) const {
    F64Array out = F64Array::zeros(vertices_.size(), 2);
    for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const Vertex& vx = vertices_[i];
        const Vec2 d = u.segment<2>(3 * vx.node) + arm(vx, u) - vx.offset;
        out(i, 0) = d.x();
        out(i, 1) = d.y();
    }
    return out;
}

F64Array InterfaceMap::velocity(const Vector& u, const Vector& v) const {
    F64Array out = F64Array::zeros(vertices_.size(), 2);
    for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const Vertex& vx = vertices_[i];
        const Vec2 r = arm(vx, u);
        const double omega = v[3 * vx.node + 2];
        out(i, 0) = v[3 * vx.node] - omega * r.y();
        out(i, 1) = v[3 * vx.node + 1] + omega * r.x();
    }
    return out;
}

Vector InterfaceMap::lump(const F64Array& forces, const Vector& u, double factor) const {
    if (forces.shape.size() != 2 || forces.rows() != vertices_.size() || forces.cols() != 2 ||
        forces.values.size() != 2 * vertices_.size())
        throw SolverError("bad_message", "structure: inputs[\"force\"] must be (" + std::to_string(vertices_.size()) +
                                          ", 2) vertex forces");
    Vector f = Vector::Zero(model_->dof_count());
    for (std::size_t i = 0; i < vertices_.size(); ++i) {
        const Vec2 force(forces(i, 0) * factor, forces(i, 1) * factor);
        // An input the structure cannot take, refused before the first sub-step uses it (docs/protocol.md,
        // ADVANCE: bad_message); "diverged" is for a solution that blew up.
        if (!std::isfinite(force.x()) || !std::isfinite(force.y()))
            throw SolverError("bad_message", "structure: inputs[\"force\"] on interface vertex " + std::to_string(i) + " (node " +
                                                 std::to_string(vertices_[i].node) + ") is not a finite number, times the "
                                                 "section depth where it is");
        const int n = vertices_[i].node;
        const Vec2 r = arm(vertices_[i], u);
        f[3 * n] += force.x();
        f[3 * n + 1] += force.y();
        f[3 * n + 2] += r.x() * force.y() - r.y() * force.x();
    }
    return f;
}

}  // namespace sphfsi::structure
