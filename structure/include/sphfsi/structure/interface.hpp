#pragma once
// The wetted surface the fluid sees. Every node of a wetted member carries two face vertices at
// -t/2 and +t/2 along the member normal; they move rigidly with the node's cross-section:
//   x_vertex = x_node + u_node + R(theta) d0,  d0 = +-t/2 n (reference offset),
// so rotations reach the fluid. A vertex force f lumps to the node as the force f and the moment
// (R(theta) d0) x f: the same rigid link, hence work-consistent and conserving force and moment.
#include <vector>

#include "sphfsi/protocol/arrays.hpp"
#include "sphfsi/structure/config.hpp"
#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

class InterfaceMap {
public:
    InterfaceMap(const Model& model, const StructureConfig& config);

    // Reference vertices (n, 2) and one CCW quad per element: (bottom_i, bottom_i+1, top_i+1, top_i).
    const protocol::InterfaceMesh& mesh() const { return mesh_; }
    std::size_t vertex_count() const { return vertices_.size(); }
    int node_of(std::size_t vertex) const { return vertices_[vertex].node; }

    // Vertex displacements and velocities (n, 2) for nodal displacements u and velocities v.
    protocol::F64Array displacement(const Vector& u) const;
    protocol::F64Array velocity(const Vector& u, const Vector& v) const;

    // Nodal forces and moments (full DOFs) equivalent to vertex forces `forces` (n, 2) times `factor`,
    // with the moment arms of configuration u. Throws SolverError bad_message on a wrong shape (the
    // protocol's code for bad array sizes), diverged on a non-finite force.
    Vector lump(const protocol::F64Array& forces, const Vector& u, double factor) const;

private:
    struct Vertex {
        int node;
        Vec2 offset;  // reference offset from the node's axis point
    };
    Vec2 arm(const Vertex& vx, const Vector& u) const;  // R(theta) offset
    const Model* model_;
    std::vector<Vertex> vertices_;
    protocol::InterfaceMesh mesh_;
};

}  // namespace sphfsi::structure
