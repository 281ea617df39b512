#pragma once
// Single 2-node plane frame element (Euler-Bernoulli: linear axial, cubic Hermitian bending).
// Element DOF order: [ux1, uy1, theta1, ux2, uy2, theta2] in global axes unless noted "local".
#include <Eigen/Core>

#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Global-to-local rotation for an axis at angle beta (local x along the axis).
Mat6 element_rotation(double beta);

// Small-displacement stiffness in local axes [u1, w1, theta1, u2, w2, theta2].
Mat6 local_linear_stiffness(const Element& e);
// ... and in global axes, for the reference orientation.
Mat6 linear_stiffness(const Element& e);

// Consistent mass: linear interpolation axially, Hermitian cubics transversally, in global axes.
Mat6 consistent_mass(const Element& e);
// Lumped mass, HRZ: half the mass at each node in both directions, rotary inertia rho A L^3 / 78
// (the consistent diagonal rescaled to the element mass), so M stays positive definite.
Mat6 lumped_mass(const Element& e);

// Work-equivalent nodal loads of a uniform load q (global axes, per unit reference length) on an
// element whose axis is at angle beta: q L/2 at each node and fixed-end moments +-q_n L^2/12.
Vec6 uniform_load(const Element& e, const Vec2& q, double beta);

// Co-rotational element (Crisfield 1991 ch. 7; Battini 2002): the element's rigid motion is taken out
// by the chord, and what is left (elongation, two end rotations relative to the chord) is small and
// treated linearly. Exact for arbitrarily large rigid rotations.
struct CorotationalState {
    double length = 0;       // current chord length L
    double beta = 0;         // current chord angle
    double elongation = 0;   // L - L0
    double theta1 = 0, theta2 = 0;  // end rotations relative to the chord
    double N = 0, M1 = 0, M2 = 0;   // local axial force and end moments
    double strain_energy = 0;
};
// `x1`, `x2` reference positions; `d` the element's global displacements. Fills the internal force
// vector and, when `tangent` is given, the consistent (material + geometric) tangent; when `material` is
// given, the material part alone, B^T k_l B: the stiffness of the element's deformation in its current
// orientation, which rigid motions do not strain (what stiffness-proportional damping multiplies).
CorotationalState corotational_element(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d, Vec6& force,
                                       Mat6* tangent, Mat6* material = nullptr);

// The local deformation e = (elongation, theta1, theta2) of a co-rotational element at displacements d.
Eigen::Vector3d corotational_deformation(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d);

// Stiffness-proportional damping of a co-rotational element over a step from deformation e0 (at the step's
// start, corotational_deformation) to displacements d: B(d)^T k_l (e(d) - e0) / h. The rate of the
// deformation itself, not B v: e is unchanged by any rigid motion of the element, so a turning element is not
// damped whatever the step, while the integrators' velocity at a step's end is the chord of a finite
// rotation and B v would stretch it (a spinning beam failed Newton from 50 rad/s; a review). `tangent`: the
// main part B^T k_l B / h (the change of B is left out: it multiplies the small e(d) - e0).
Vec6 corotational_deformation_damping(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d,
                                      const Eigen::Vector3d& e0, double h, Mat6* tangent);

// Wraps an angle to (-pi, pi].
double wrap_angle(double a);

}  // namespace sphfsi::structure
