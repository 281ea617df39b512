#pragma once
// Natural modes of the constrained, undeformed structure: K phi = omega^2 M phi.
#include <Eigen/Core>

#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

struct Modes {
    Eigen::VectorXd omega2;  // ascending, [rad^2/s^2]; rigid-body modes have ~0
    Eigen::MatrixXd shapes;  // full-DOF columns, mass-normalized (phi^T M phi = 1)
    int rigid_body = 0;      // how many leading modes are rigid-body modes
    int vectors = 0;         // subspace iteration: the vectors of the run that converged (0: the dense solver)
    double omega(int i) const;  // sqrt(max(omega2, 0))
};

// The `count` lowest modes (fewer if the structure has fewer free DOFs). Small models use a dense
// generalized eigensolver; larger ones subspace iteration (Bathe) with Rayleigh-Ritz, on a sparse
// LDLT factorization of K. Rigid-body modes (from the geometry and supports) are exact and deflated: the
// iteration runs M-orthogonal to them, with K grounded at as many coordinates as there are rigid modes.
Modes lowest_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count);

// All modes by the dense solver (tests, small models).
Modes dense_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M);

// The same by subspace iteration regardless of size (exposed so tests can check it against dense_modes, and
// its retries with more vectors by lowering the iterations a run may take).
Modes subspace_modes(const Model& model, const SparseMatrix& K, const SparseMatrix& M, int count,
                     int max_iterations = 200);

}  // namespace sphfsi::structure
