#pragma once
// Sparse symmetric solve on the free DOFs. LDL^T (Eigen SimplicialLDLT) with the fill-reducing ordering
// computed once per sparsity pattern; falls back to SparseLU if LDL^T meets a zero pivot.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

class ReducedSolver {
public:
    // Returns false when the matrix is singular (to working precision).
    bool factorize(const SparseMatrix& A);
    Vector solve(const Vector& b) const;
    int factorizations() const { return count_; }
    // Smallest / largest pivot magnitude of the last LDL^T attempt; tiny means (nearly) singular.
    double pivot_ratio() const { return pivot_ratio_; }

private:
    Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
    Eigen::SparseLU<SparseMatrix> lu_;
    bool use_lu_ = false;
    Eigen::Index analyzed_rows_ = -1, analyzed_nonzeros_ = -1;
    int count_ = 0;
    double pivot_ratio_ = 1.0;
};

}  // namespace sphfsi::structure
