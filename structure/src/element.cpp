#include "sphfsi/structure/element.hpp"

#include <cmath>
#include <numbers>

namespace sphfsi::structure {

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

    const double c = std::cos(s.beta), sn = std::sin(s.beta), L = s.length;
    Vec6 r, z;
    r << -c, -sn, 0, c, sn, 0;   // d(L) / d(p)
    z << sn, -c, 0, -sn, c, 0;   // L d(beta) / d(p)
    Eigen::Matrix<double, 3, 6> B;
    B.row(0) = r.transpose();
    B.row(1) = -z.transpose() / L;
    B.row(2) = -z.transpose() / L;
    B(1, 2) += 1.0;
    B(2, 5) += 1.0;
    force = B.transpose() * Eigen::Vector3d(s.N, s.M1, s.M2);
    if (tangent || material) {
        Eigen::Matrix3d kl;
        kl << e.EA / L0, 0, 0, 0, 4 * k, 2 * k, 0, 2 * k, 4 * k;
        const Mat6 km = B.transpose() * kl * B;
        if (material) *material = km;
        if (tangent)
            *tangent = km + (s.N / L) * z * z.transpose() + ((s.M1 + s.M2) / (L * L)) * (r * z.transpose() + z * r.transpose());
    }
    return s;
}

}  // namespace sphfsi::structure
