#include "sphfsi/structure/modal.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <cmath>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {
namespace {

// Above this many free DOFs the O(n^3) dense solver gets slower than subspace iteration.
constexpr int dense_limit = 150;

// Rough square of the highest frequency, from the diagonals: the scale for "numerically zero" omega^2.
double omega2_scale(const SparseMatrix& Kr, const SparseMatrix& Mr) {
    double s = 0;
    for (int i = 0; i < Kr.rows(); ++i) s = std::max(s, Kr.coeff(i, i) / Mr.coeff(i, i));
    return s;
}

void count_rigid(Modes& modes, double scale) {
    modes.rigid_body = 0;
    while (modes.rigid_body < modes.omega2.size() && modes.omega2[modes.rigid_body] < 1e-10 * scale)
        ++modes.rigid_body;
}

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
    count_rigid(modes, omega2_scale(Kr, Mr));
    return modes;
}

Modes subspace_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count) {
    const SparseMatrix Kr = model.T.transpose() * K * model.T;
    const SparseMatrix Mr = model.T.transpose() * M * model.T;
    const int n = static_cast<int>(Kr.rows());
    const double scale = omega2_scale(Kr, Mr);

    Eigen::SimplicialLDLT<SparseMatrix> ldlt(Kr);
    double shift = 0.0;
    bool definite = ldlt.info() == Eigen::Success;
    if (definite) {
        const auto& d = ldlt.vectorD();
        definite = d.minCoeff() > 1e-12 * d.maxCoeff();
    }
    if (!definite) {
        // Unsupported structure: factorize K + s M instead (s > 0 keeps it definite). The Ritz values
        // below still use K and M, so the shift slows convergence but does not bias the result.
        shift = 1e-8 * scale;
        ldlt.compute(SparseMatrix(Kr + shift * Mr));
        if (ldlt.info() != Eigen::Success)
            throw protocol::SolverError("internal", "structure: cannot factorize K for the modal analysis");
        count += 3;  // room for the rigid-body modes (zero frequency) in front of the elastic ones
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
    count_rigid(modes, scale);
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
