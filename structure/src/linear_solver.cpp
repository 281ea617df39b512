#include "sphfsi/structure/linear_solver.hpp"

namespace sphfsi::structure {

bool ReducedSolver::factorize(const SparseMatrix& A) {
    ++count_;
    // The pattern of every matrix we factorize is fixed by the mesh, so the ordering is reused;
    // re-analyse only if the pattern (seen through its size) changed.
    if (A.rows() != analyzed_rows_ || A.nonZeros() != analyzed_nonzeros_) {
        ldlt_.analyzePattern(A);
        analyzed_rows_ = A.rows();
        analyzed_nonzeros_ = A.nonZeros();
    }
    ldlt_.factorize(A);
    use_lu_ = false;
    pivot_ratio_ = 0.0;
    if (ldlt_.info() == Eigen::Success) {
        const Vector d = ldlt_.vectorD().cwiseAbs();  // evaluate: vectorD() returns a temporary
        pivot_ratio_ = d.size() ? d.minCoeff() / d.maxCoeff() : 1.0;
        if (pivot_ratio_ > 1e-14) return true;
    }
    // A (near) zero pivot without pivoting does not yet mean singular: let partial pivoting decide.
    use_lu_ = true;
    lu_.compute(A);
    return lu_.info() == Eigen::Success;
}

Vector ReducedSolver::solve(const Vector& b) const { return use_lu_ ? Vector(lu_.solve(b)) : Vector(ldlt_.solve(b)); }

}  // namespace sphfsi::structure
