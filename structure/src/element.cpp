#include "sphfsi/structure/element.hpp"

#include <cmath>
#include <numbers>

namespace sphfsi::structure {
namespace {

// The chord's frame at angle beta and length L: r = d(L)/d(p), z = L d(beta)/d(p), and Crisfield's B, the
// rates of the local deformation (elongation, theta1, theta2) from the element's six global rates.
struct ChordFrame {
    Vec6 r, z;
    Eigen::Matrix<double, 3, 6> B;
};
ChordFrame chord_frame(double beta, double L) {
    const double c = std::cos(beta), sn = std::sin(beta);
    ChordFrame f;
    f.r << -c, -sn, 0, c, sn, 0;
    f.z << sn, -c, 0, -sn, c, 0;
    f.B.row(0) = f.r.transpose();
    f.B.row(1) = -f.z.transpose() / L;
    f.B.row(2) = -f.z.transpose() / L;
    f.B(1, 2) += 1.0;
    f.B(2, 5) += 1.0;
    return f;
}

// k_l: the local stiffness of (elongation, theta1, theta2).
Eigen::Matrix3d local_stiffness(const Element& e) {
    const double k = e.EI / e.L0;
    Eigen::Matrix3d kl;
    kl << e.EA / e.L0, 0, 0, 0, 4 * k, 2 * k, 0, 2 * k, 4 * k;
    return kl;
}

}  // namespace

double wrap_angle(double a) {
    const double two_pi = 2.0 * std::numbers::pi;
    return a - two_pi * std::round(a / two_pi);
}

Mat6 element_rotation(double beta) {
    const double c = std::cos(beta), s = std::sin(beta);
    Mat6 R = Mat6::Zero();
    for (int n = 0; n < 2; ++n) {
        const int o = 3 * n;
        R(o, o) = c;
        R(o, o + 1) = s;
        R(o + 1, o) = -s;
        R(o + 1, o + 1) = c;
        R(o + 2, o + 2) = 1.0;
    }
    return R;
}

Mat6 local_linear_stiffness(const Element& e) {
    const double L = e.L0, a = e.EA / L, b = e.EI / (L * L * L);
    Mat6 k = Mat6::Zero();
    k(0, 0) = k(3, 3) = a;
    k(0, 3) = k(3, 0) = -a;
    const int w[4] = {1, 2, 4, 5};
    const double kb[4][4] = {{12, 6 * L, -12, 6 * L},
                             {6 * L, 4 * L * L, -6 * L, 2 * L * L},
                             {-12, -6 * L, 12, -6 * L},
                             {6 * L, 2 * L * L, -6 * L, 4 * L * L}};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) k(w[i], w[j]) = b * kb[i][j];
    return k;
}

Mat6 linear_stiffness(const Element& e) {
    const Mat6 R = element_rotation(e.beta0);
    return R.transpose() * local_linear_stiffness(e) * R;
}

Mat6 consistent_mass(const Element& e) {
    const double L = e.L0, m = e.rhoA * L;
    Mat6 k = Mat6::Zero();
    k(0, 0) = k(3, 3) = m / 3.0;
    k(0, 3) = k(3, 0) = m / 6.0;
    const int w[4] = {1, 2, 4, 5};
    const double mb[4][4] = {{156, 22 * L, 54, -13 * L},
                             {22 * L, 4 * L * L, 13 * L, -3 * L * L},
                             {54, 13 * L, 156, -22 * L},
                             {-13 * L, -3 * L * L, -22 * L, 4 * L * L}};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) k(w[i], w[j]) = m / 420.0 * mb[i][j];
    const Mat6 R = element_rotation(e.beta0);
    return R.transpose() * k * R;
}

Mat6 lumped_mass(const Element& e) {
    const double L = e.L0, m = e.rhoA * L;
    Mat6 k = Mat6::Zero();
    k(0, 0) = k(1, 1) = k(3, 3) = k(4, 4) = m / 2.0;
    k(2, 2) = k(5, 5) = m * L * L / 78.0;
    return k;  // isotropic in translation: no rotation needed
}

Vec6 uniform_load(const Element& e, const Vec2& q, double beta) {
    const double L = e.L0;
    const double qn = -std::sin(beta) * q.x() + std::cos(beta) * q.y();  // component along the axis normal
    Vec6 f;
    f << q.x() * L / 2, q.y() * L / 2, qn * L * L / 12, q.x() * L / 2, q.y() * L / 2, -qn * L * L / 12;
    return f;
}

CorotationalState corotational_element(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d, Vec6& force,
                                       Mat6* tangent, Mat6* material) {
    CorotationalState s;
    const Vec2 X = x2 - x1;                         // reference chord
    const Vec2 du(d[3] - d[0], d[4] - d[1]);        // relative translation
    const Vec2 x = X + du;                          // current chord
    s.length = x.norm();
    s.beta = std::atan2(x.y(), x.x());
    // L - L0 without cancellation: (|X + du|^2 - |X|^2) / (L + L0).
    s.elongation = (2.0 * X.dot(du) + du.squaredNorm()) / (s.length + e.L0);
    // Rigid rotation of the chord, measured directly between the two chords (accurate, in (-pi, pi]).
    const double alpha = std::atan2(X.x() * x.y() - X.y() * x.x(), X.dot(x));
    s.theta1 = wrap_angle(d[2] - alpha);
    s.theta2 = wrap_angle(d[5] - alpha);

    const double L0 = e.L0, k = e.EI / L0;
    s.N = e.EA / L0 * s.elongation;
    s.M1 = k * (4 * s.theta1 + 2 * s.theta2);
    s.M2 = k * (2 * s.theta1 + 4 * s.theta2);
    s.strain_energy = 0.5 * s.N * s.elongation + 0.5 * (s.M1 * s.theta1 + s.M2 * s.theta2);

    const double L = s.length;
    const ChordFrame f = chord_frame(s.beta, L);
    const Vec6 &r = f.r, &z = f.z;
    const auto& B = f.B;
    force = B.transpose() * Eigen::Vector3d(s.N, s.M1, s.M2);
    if (tangent || material) {
        const Mat6 km = B.transpose() * local_stiffness(e) * B;
        if (material) *material = km;
        if (tangent)
            *tangent = km + (s.N / L) * z * z.transpose() + ((s.M1 + s.M2) / (L * L)) * (r * z.transpose() + z * r.transpose());
    }
    return s;
}

Eigen::Vector3d corotational_deformation(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d) {
    Vec6 unused;
    const CorotationalState s = corotational_element(e, x1, x2, d, unused, nullptr);
    return {s.elongation, s.theta1, s.theta2};
}

Vec6 corotational_deformation_damping(const Element& e, const Vec2& x1, const Vec2& x2, const Vec6& d,
                                      const Eigen::Vector3d& e0, double h, Mat6* tangent) {
    Vec6 unused;
    const CorotationalState now = corotational_element(e, x1, x2, d, unused, nullptr);
    const Eigen::Vector3d rate((now.elongation - e0[0]) / h, wrap_angle(now.theta1 - e0[1]) / h,
                               wrap_angle(now.theta2 - e0[2]) / h);
    const ChordFrame f = chord_frame(now.beta, now.length);
    const Eigen::Matrix3d kl = local_stiffness(e);
    if (tangent) *tangent = f.B.transpose() * kl * f.B / h;
    return f.B.transpose() * (kl * rate);
}

}  // namespace sphfsi::structure
