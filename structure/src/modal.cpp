#include "sphfsi/structure/modal.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {
namespace {

// Above this many free DOFs the O(n^3) dense solver gets slower than subspace iteration.
constexpr int dense_limit = 150;

// Rough square of the highest frequency, from the diagonals: the scale of the shift for a singular K.
double omega2_scale(const SparseMatrix& Kr, const SparseMatrix& Mr) {
    double s = 0;
    for (int i = 0; i < Kr.rows(); ++i) s = std::max(s, Kr.coeff(i, i) / Mr.coeff(i, i));
    return s;
}

// How many rigid-body modes the structure has: the dimension of the rigid motions (two translations and
// a rotation per connected part; members are welded where they meet, so there are no other mechanisms)
// that the supports leave admissible, i.e. that lie in range(T). Counted from the geometry, not from
// small eigenvalues: the lowest elastic omega^2 of a fine mesh falls like 1/n^4 against the highest, so a
// fixed "numerically zero" fraction of the highest miscounted a 400-element cantilever as having no
// elastic modes at all.
int rigid_motion_count(const Model& model) {
    const int n = model.node_count();
    std::vector<int> part(n);  // union-find over the elements: which connected part each node is in
    for (int i = 0; i < n; ++i) part[i] = i;
    auto root = [&](int i) {
        while (part[i] != i) i = part[i] = part[part[i]];
        return i;
    };
    for (const Element& e : model.elements) part[root(e.n1)] = root(e.n2);
    std::vector<int> column(n, -1);
    int parts = 0;
    for (int i = 0; i < n; ++i)
        if (column[root(i)] < 0) column[root(i)] = parts++;

    // Unit-scaled rigid motions of each part: ux, uy, and a rotation about the origin in units of the
    // characteristic length (so all three columns have comparable norms).
    const double ell = model.characteristic_length;
    Eigen::MatrixXd R = Eigen::MatrixXd::Zero(model.dof_count(), 3 * parts);
    for (int i = 0; i < n; ++i) {
        const int c = 3 * column[root(i)];
        R(3 * i, c) = 1.0;
        R(3 * i + 1, c + 1) = 1.0;
        R(3 * i, c + 2) = -model.nodes[i].y() / ell;
        R(3 * i + 1, c + 2) = model.nodes[i].x() / ell;
        R(3 * i + 2, c + 2) = 1.0 / ell;
    }
    R.colwise().normalize();
    // T's columns are orthonormal (unit directions on disjoint DOFs), so R - T T^T R is the part of each
    // motion the supports forbid; its null space is the admissible rigid motions. Its singular values are
    // roundoff (~1e-16) on that space and at least ~1/sqrt(nodes) off it (one supported node of a unit motion).
    const Eigen::MatrixXd violation = R - model.T * (model.T.transpose() * R);
    const Eigen::VectorXd sigma = Eigen::JacobiSVD<Eigen::MatrixXd>(violation).singularValues();
    return static_cast<int>((sigma.array() < 1e-8).count());
}

void count_rigid(Modes& modes, int rigid) { modes.rigid_body = std::min<int>(rigid, static_cast<int>(modes.omega2.size())); }

}  // namespace

double Modes::omega(int i) const { return std::sqrt(std::max(omega2[i], 0.0)); }

Modes dense_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M) {
    const SparseMatrix Kr = model.T.transpose() * K * model.T;
    const SparseMatrix Mr = model.T.transpose() * M * model.T;
    const Eigen::MatrixXd Kd(Kr), Md(Mr);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd, Md);
    if (es.info() != Eigen::Success) throw protocol::SolverError("internal", "structure: modal analysis failed");
    Modes modes;
    modes.omega2 = es.eigenvalues();
    modes.shapes = model.T * es.eigenvectors();
    count_rigid(modes, rigid_motion_count(model));
    return modes;
}

Modes subspace_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count) {
    const SparseMatrix Kr = model.T.transpose() * K * model.T;
    const SparseMatrix Mr = model.T.transpose() * M * model.T;
    const int n = static_cast<int>(Kr.rows());
    const double scale = omega2_scale(Kr, Mr);

    const int rigid = rigid_motion_count(model);
    Eigen::SimplicialLDLT<SparseMatrix> ldlt;
    double shift = 0.0;
    if (rigid == 0) ldlt.compute(Kr);
    if (rigid > 0 || ldlt.info() != Eigen::Success) {
        // Unsupported structure: factorize K + s M instead (s > 0 keeps it definite). The Ritz values
        // below still use K and M, so the shift slows convergence but does not bias the result.
        shift = 1e-8 * scale;
        ldlt.compute(SparseMatrix(Kr + shift * Mr));
        if (ldlt.info() != Eigen::Success)
            throw protocol::SolverError("internal", "structure: cannot factorize K for the modal analysis");
        count += rigid;  // room for the rigid-body modes (zero frequency) in front of the elastic ones
    }
    count = std::min(count, n);
    const int p = std::min(n, std::max(2 * count, count + 8));  // Bathe's subspace size

    // Deterministic start vectors: the diagonal ratio (excites the softest DOFs) and smooth waves.
    Eigen::MatrixXd X(n, p);
    for (int i = 0; i < n; ++i) {
        X(i, 0) = Mr.coeff(i, i) / Kr.coeff(i, i);
        for (int j = 1; j < p; ++j) X(i, j) = std::sin(0.37 * (i + 1) * j + 0.11 * j);
    }
    Modes modes;
    Eigen::VectorXd previous = Eigen::VectorXd::Constant(p, -1.0);
    for (int iteration = 0; iteration < 200; ++iteration) {
        const Eigen::MatrixXd MX = Mr * X;
        const Eigen::MatrixXd Y = ldlt.solve(MX);
        // Projected stiffness from K Y = M X - s M Y instead of multiplying K Y out: for smooth
        // (low) modes |K Y| << |K| |Y| and the product would lose most of its digits.
        const Eigen::MatrixXd Mp = Y.transpose() * (Mr * Y);
        const Eigen::MatrixXd Kp = Y.transpose() * MX - shift * Mp;
        Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Kp + Kp.transpose()),
                                                                      0.5 * (Mp + Mp.transpose()));
        X = Y * es.eigenvectors();
        const Eigen::VectorXd lambda = es.eigenvalues();
        double change = 0;
        for (int k = 0; k < count; ++k)
            change = std::max(change, std::abs(lambda[k] - previous[k]) / std::max(std::abs(lambda[k]), 1e-12 * scale));
        previous = lambda;
        if (change < 1e-12) break;
    }
    modes.omega2 = previous.head(count);
    modes.shapes = model.T * X.leftCols(count);
    count_rigid(modes, rigid);
    return modes;
}

Modes lowest_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count) {
    if (model.free_count() <= dense_limit) {
        Modes all = dense_modes(model, K, M);
        const int c = std::min<int>(count + all.rigid_body, static_cast<int>(all.omega2.size()));
        Modes m;
        m.omega2 = all.omega2.head(c);
        m.shapes = all.shapes.leftCols(c);
        m.rigid_body = all.rigid_body;
        return m;
    }
    return subspace_modes(model, K, M, count);
}

}  // namespace sphfsi::structure
