#include "sphfsi/structure/modal.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {
namespace {

// Above this many free DOFs the O(n^3) dense solver gets slower than subspace iteration.
constexpr int dense_limit = 150;

// Rough square of the highest frequency, from the diagonals: the floor of the convergence test.
double omega2_scale(const SparseMatrix& Kr, const SparseMatrix& Mr) {
    double s = 0;
    for (int i = 0; i < Kr.rows(); ++i) s = std::max(s, Kr.coeff(i, i) / Mr.coeff(i, i));
    return s;
}

// The rigid-body modes the structure has, as columns in the free coordinates q (u = T q): the rigid motions
// (two translations and a rotation per connected part; members are welded where they meet, so there are no
// other mechanisms) that the supports leave admissible, i.e. that lie in range(T). Found from the geometry,
// not from small eigenvalues: the lowest elastic omega^2 of a fine mesh falls like 1/n^4 against the highest,
// so a fixed "numerically zero" fraction of the highest miscounted a 400-element cantilever as having no
// elastic modes at all.
Eigen::MatrixXd rigid_motions(const Model& model) {
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
    std::vector<std::vector<int>> nodes_of(parts);
    for (int i = 0; i < n; ++i) nodes_of[column[root(i)]].push_back(i);

    // The parts share no DOF, so each is tested alone: one SVD of all 3 x parts motions at once cost minutes
    // for a few hundred separate posts (800 clamped posts of 5 elements: no READY after 100 s, a review,
    // 2026-11-27), while each part's own is 3 columns.
    std::vector<Vector> admissible;
    for (const std::vector<int>& nodes : nodes_of) {
        Vec2 centroid = Vec2::Zero();
        for (int i : nodes) centroid += model.nodes[i];
        centroid /= static_cast<double>(nodes.size());
        // Rigid motions of the part: ux, uy, and a rotation about its centroid, which makes the three columns
        // orthogonal (a rotation about a far origin would be nearly a translation, and the rank test below
        // would lose it); each column then scaled to unit norm.
        Eigen::MatrixXd R = Eigen::MatrixXd::Zero(model.dof_count(), 3);
        for (int i : nodes) {
            const Vec2 r = model.nodes[i] - centroid;
            R(3 * i, 0) = 1.0;
            R(3 * i + 1, 1) = 1.0;
            R(3 * i, 2) = -r.y();
            R(3 * i + 1, 2) = r.x();
            R(3 * i + 2, 2) = 1.0;
        }
        R.colwise().normalize();
        // T's columns are orthonormal (unit directions on disjoint DOFs), so R - T T^T R is the part of each
        // motion the supports forbid; its null space is the admissible rigid motions. Its singular values
        // are roundoff (~1e-16) on that space and of order 1/sqrt(nodes of the part) off it (one supported
        // node's share of a unit motion). Only the part's own rows can be non-zero.
        const Eigen::MatrixXd violation = R - model.T * (model.T.transpose() * R);
        Eigen::MatrixXd own(3 * static_cast<Eigen::Index>(nodes.size()), 3);
        for (std::size_t k = 0; k < nodes.size(); ++k) own.middleRows(3 * static_cast<Eigen::Index>(k), 3) = violation.middleRows(3 * nodes[k], 3);
        Eigen::JacobiSVD<Eigen::MatrixXd> svd(own, Eigen::ComputeThinV);
        for (int j = 0; j < svd.singularValues().size(); ++j)
            if (svd.singularValues()[j] < 1e-8) admissible.push_back(R * svd.matrixV().col(j));
    }
    Eigen::MatrixXd C(model.dof_count(), static_cast<Eigen::Index>(admissible.size()));
    for (std::size_t k = 0; k < admissible.size(); ++k) C.col(static_cast<Eigen::Index>(k)) = admissible[k];
    return model.T.transpose() * C;  // admissible: T times this is C itself
}

void count_rigid(Modes& modes, int rigid) { modes.rigid_body = std::min<int>(rigid, static_cast<int>(modes.omega2.size())); }

}  // namespace

double Modes::omega(int i) const { return std::sqrt(std::max(omega2[i], 0.0)); }

Modes dense_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M) {
    const SparseMatrix Kr = model.T.transpose() * K * model.T;
    const SparseMatrix Mr = model.T.transpose() * M * model.T;
    const Eigen::MatrixXd Kd(Kr), Md(Mr);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd, Md);
    // Within the schema's bounds only an extreme combination of them fails here; name what sets K and M.
    if (es.info() != Eigen::Success)
        throw protocol::SolverError("bad_config", "structure: the modal analysis did not converge; check "
                                                  "structure.material.E and rho, structure.section.thickness and depth, "
                                                  "and the members' lengths and n_elements for extreme values");
    Modes modes;
    modes.omega2 = es.eigenvalues();
    modes.shapes = model.T * es.eigenvectors();
    count_rigid(modes, static_cast<int>(rigid_motions(model).cols()));
    return modes;
}

Modes subspace_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count, int max_iterations) {
    const SparseMatrix Kr = model.T.transpose() * K * model.T;
    const SparseMatrix Mr = model.T.transpose() * M * model.T;
    const int n = static_cast<int>(Kr.rows());
    const double scale = omega2_scale(Kr, Mr);

    // Rigid-body modes (unsupported or partly supported structures) are known exactly: M-orthonormalise them,
    // and iterate on the elastic modes only, M-orthogonal to them ("inertia relief"). A shift K + s M instead
    // must stay far below the lowest elastic omega^2, which falls like 1/n^4: at 3000 free-free elements a
    // shift of 1e-8 of the highest swamped it, and the iteration returned 1180 Hz for a 106 Hz mode.
    Eigen::MatrixXd rigid = rigid_motions(model);
    const int r = static_cast<int>(rigid.cols());
    std::vector<int> grounded;  // r free coordinates held at zero so that K becomes definite
    if (r > 0) {
        const Eigen::LLT<Eigen::MatrixXd> gram(rigid.transpose() * (Mr * rigid));
        rigid = gram.matrixL().solve(rigid.transpose()).transpose();  // now rigid^T M rigid = I
        // The coordinates where the rigid modes are most independent (column-pivoted QR): holding them stops
        // every rigid motion, and with no mechanisms the rest of K is definite.
        const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(rigid.transpose());
        for (int k = 0; k < r; ++k) grounded.push_back(qr.colsPermutation().indices()[k]);
    }
    std::vector<char> held(static_cast<std::size_t>(n), 0);
    for (int i : grounded) held[static_cast<std::size_t>(i)] = 1;
    std::vector<Eigen::Triplet<double>> kept;
    for (int c = 0; c < Kr.outerSize(); ++c)
        for (SparseMatrix::InnerIterator it(Kr, c); it; ++it)
            if (!held[static_cast<std::size_t>(it.row())] && !held[static_cast<std::size_t>(it.col())])
                kept.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    for (int i : grounded) kept.emplace_back(i, i, Kr.coeff(i, i));
    SparseMatrix Kg(n, n);
    Kg.setFromTriplets(kept.begin(), kept.end());
    const Eigen::SimplicialLDLT<SparseMatrix> ldlt(Kg);
    if (ldlt.info() != Eigen::Success)
        throw protocol::SolverError("internal", "structure: cannot factorize K for the modal analysis");

    auto deflate = [&](Eigen::MatrixXd& Z) {
        if (r > 0) Z -= rigid * (rigid.transpose() * (Mr * Z));
    };
    count = std::min(count, n - r);

    // One run of subspace iteration with p vectors; `change` is the last relative change of the `count` lowest
    // Ritz values, NaN when the projected eigenproblem failed or gave a non-finite value.
    struct Run {
        Eigen::VectorXd lambda;
        Eigen::MatrixXd X;
        double change = std::numeric_limits<double>::infinity();
    };
    auto iterate = [&](int p) {
        // Deterministic start vectors: the diagonal ratio (excites the softest DOFs) and smooth waves.
        Run run;
        run.X.resize(n, p);
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < p; ++j)
                run.X(i, j) = j == 0 ? Mr.coeff(i, i) / Kr.coeff(i, i) : std::sin(0.37 * (i + 1) * j + 0.11 * j);
        }
        deflate(run.X);
        run.lambda = Eigen::VectorXd::Constant(p, -1.0);
        for (int iteration = 0; iteration < max_iterations; ++iteration) {
            const Eigen::MatrixXd MX = Mr * run.X;
            // M X is M-orthogonal to the rigid modes (self-equilibrated), so the reactions at the held
            // coordinates are zero and the grounded solve solves K Y = M X itself; its rigid part is removed.
            Eigen::MatrixXd F = MX;
            for (int i : grounded) F.row(i).setZero();
            Eigen::MatrixXd Y = ldlt.solve(F);
            deflate(Y);
            // Projected stiffness from K Y = M X instead of multiplying K Y out: for smooth (low) modes
            // |K Y| << |K| |Y| and the product would lose most of its digits.
            const Eigen::MatrixXd Mp = Y.transpose() * (Mr * Y);
            const Eigen::MatrixXd Kp = Y.transpose() * MX;
            Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Kp + Kp.transpose()),
                                                                          0.5 * (Mp + Mp.transpose()));
            if (es.info() != Eigen::Success || !es.eigenvalues().allFinite()) {
                run.change = std::numeric_limits<double>::quiet_NaN();
                return run;
            }
            run.X = Y * es.eigenvectors();
            const Eigen::VectorXd& lambda = es.eigenvalues();
            run.change = 0;
            for (int k = 0; k < count; ++k)
                run.change = std::max(run.change, std::abs(lambda[k] - run.lambda[k]) /
                                                      std::max(std::abs(lambda[k]), 1e-12 * scale));
            run.lambda = lambda;
            if (run.change < 1e-12) break;
        }
        return run;
    };
    // Bathe's subspace size first. A run that has not settled in 200 iterations (the wanted modes' ratio to
    // the first one left out is close to 1) is repeated with twice and then four times the vectors (at most
    // n - r, where the Ritz values are exact); more would cost dense work of order n p^2 for little. A projected
    // problem that broke down is an error at once: more vectors do not mend a K that is nearly singular.
    const int p0 = std::min(n - r, std::max(2 * count, count + 8));
    Run run;
    for (int p = p0;; p = std::min(n - r, 2 * p)) {
        run = iterate(p);
        if (run.change <= 1e-8) break;
        if (std::isnan(run.change))
            throw protocol::SolverError("internal", "structure: the modal analysis broke down (the projected "
                                                    "eigenproblem with " + std::to_string(p) +
                                                    " vectors failed or gave non-finite values)");
        if (p == n - r || p >= 4 * p0)
            throw protocol::SolverError("internal", "structure: the modal analysis did not converge in " +
                                                    std::to_string(max_iterations) + " subspace iterations with " +
                                                    std::to_string(p) + " vectors (relative change " +
                                                    std::to_string(run.change) + ")");
    }
    Modes modes;
    modes.omega2 = Eigen::VectorXd::Zero(r + count);
    modes.omega2.tail(count) = run.lambda.head(count);
    Eigen::MatrixXd shapes(n, r + count);
    shapes << rigid, run.X.leftCols(count);
    modes.shapes = model.T * shapes;
    modes.rigid_body = r;
    modes.vectors = static_cast<int>(run.X.cols());
    return modes;
}

Modes lowest_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count) {
    if (model.free_count() <= dense_limit) {
        Modes all = dense_modes(model, K, M);
        // Its absolute error is about eps * w^2_max: where that is above 1e-8 of the lowest elastic w^2 (a very
        // short element's stiffness: a 1e-5 m stub put f1 30 % high; a review, 2026-11-28), subspace
        // iteration on K^-1 resolves the low end instead.
        const int r = all.rigid_body;
        const bool resolved = r < all.omega2.size() && all.omega2[r] > 0 &&
                              std::numeric_limits<double>::epsilon() * all.omega2.maxCoeff() <= 1e-8 * all.omega2[r];
        if (!resolved && r < all.omega2.size()) return subspace_modes(model, K, M, count);
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
