#pragma once
// The discrete frame: nodes, 2-node beam elements and the support constraints. Degrees of freedom are
// numbered node by node: [ux, uy, theta] of node i at 3i, 3i+1, 3i+2.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "sphfsi/structure/config.hpp"

namespace sphfsi::structure {

using Vec2 = Eigen::Vector2d;
using Vector = Eigen::VectorXd;
using SparseMatrix = Eigen::SparseMatrix<double>;

struct Element {
    int n1 = 0, n2 = 0;  // node indices
    int member = 0;
    double L0 = 0;       // reference length [m]
    double beta0 = 0;    // reference angle of the axis n1 -> n2 [rad]
    double EA = 0, EI = 0, rhoA = 0;  // per the whole depth b [N], [N m^2], [kg/m]
};

struct Model {
    std::vector<Vec2> nodes;                     // reference positions
    std::vector<Element> elements;
    std::vector<std::vector<int>> member_nodes;  // each member's nodes from start to end
    std::vector<std::vector<int>> member_elements;
    // Columns span the admissible displacements: u = T q with q the free coordinates. Clamped nodes
    // get no column, pinned ones only theta, rollers the tangent of the rolling surface and theta.
    SparseMatrix T;
    double characteristic_length = 1.0;  // largest member length, for tolerances

    int node_count() const { return static_cast<int>(nodes.size()); }
    int dof_count() const { return 3 * node_count(); }
    int free_count() const { return static_cast<int>(T.cols()); }
    // Index of the node at p (within the scene tolerance), or -1.
    int node_at(const Point2& p) const;
};

// Builds nodes (merging coincident member ends), elements and constraints. Throws
// protocol::SolverError("bad_config", ...) on problems the schema cannot see.
Model build_model(const StructureConfig& config);

}  // namespace sphfsi::structure
