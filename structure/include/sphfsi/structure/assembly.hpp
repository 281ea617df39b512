#pragma once
// Global matrices and force vectors from the element routines (all in full DOF numbering; the
// support constraints are applied later through Model::T).
#include "sphfsi/structure/element.hpp"
#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

SparseMatrix assemble_linear_stiffness(const Model& model);
SparseMatrix assemble_mass(const Model& model, MassKind kind);

// Co-rotational internal force at displacement u; tangent, strain energy and the tangent's material part
// (corotational_element) when asked for.
Vector corotational_internal_force(const Model& model, const Vector& u, SparseMatrix* tangent, double* strain_energy,
                                   SparseMatrix* material = nullptr);

// Every element's local deformation at u (corotational_deformation), in element order.
std::vector<Eigen::Vector3d> corotational_deformations(const Model& model, const Vector& u);

// The elements' stiffness-proportional damping over a step of length h from the deformations `at_start`
// (corotational_deformations at the step's start) to u, summed (corotational_deformation_damping: zero
// for rigid motion); its main tangent part when asked for.
Vector corotational_deformation_damping(const Model& model, const Vector& u, const std::vector<Eigen::Vector3d>& at_start,
                                        double h, SparseMatrix* tangent);

// Current chord angle of every element (reference angle when `u` is empty).
std::vector<double> element_angles(const Model& model, const Vector& u);

}  // namespace sphfsi::structure
