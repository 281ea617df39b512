// Element-level checks: rigid-body invariance, symmetry, mass totals, and the co-rotational tangent
// against finite differences of the internal force (the "consistent tangent" claim).
#include <doctest/doctest.h>

#include <cmath>
#include <Eigen/Geometry>
#include <numbers>

#include "sphfsi/structure/element.hpp"

using namespace sphfsi::structure;

namespace {
Element make_element(double beta, double L = 0.7) {
    Element e;
    e.n1 = 0;
    e.n2 = 1;
    e.L0 = L;
    e.beta0 = beta;
    e.EA = 2.1e9;
    e.EI = 1.75e4;
    e.rhoA = 78.5;
    return e;
}
Vec2 end_of(const Element& e) { return e.L0 * Vec2(std::cos(e.beta0), std::sin(e.beta0)); }

// Displacements of a rigid rotation by phi about node 1 plus a translation.
Vec6 rigid(const Element& e, double phi, Vec2 shift) {
    const Vec2 X = end_of(e);
    const Vec2 x = Eigen::Rotation2Dd(phi) * X;
    Vec6 d;
    d << shift.x(), shift.y(), phi, shift.x() + x.x() - X.x(), shift.y() + x.y() - X.y(), phi;
    return d;
}
}  // namespace

TEST_SUITE("elements") {
TEST_CASE("linear stiffness: symmetric, three zero-energy rigid modes") {
    const Element e = make_element(0.4);
    const Mat6 K = linear_stiffness(e);
    CHECK((K - K.transpose()).norm() <= 1e-12 * K.norm());
    // Infinitesimal rigid motions: two translations and a rotation about node 1.
    Vec6 tx, ty, rot;
    tx << 1, 0, 0, 1, 0, 0;
    ty << 0, 1, 0, 0, 1, 0;
    const Vec2 X = end_of(e);
    rot << 0, 0, 1, -X.y(), X.x(), 1;
    for (const Vec6& m : {tx, ty, rot}) CHECK((K * m).norm() <= 1e-10 * K.norm());
}

TEST_CASE("the lumped mass is HRZ's diagonal") {
    // Hinton, Rock & Zienkiewicz (1976) for the cubic beam: m/2 at each node in translation and the
    // consistent matrix's rotary terms scaled to the same total, m L^2 / 78 (the modal test shows the
    // frequencies it gives; this pins the entries, which the element's total mass alone does not).
    const Element e = make_element(0.9);
    const double m = e.rhoA * e.L0;
    Mat6 hrz = Mat6::Zero();
    hrz.diagonal() << m / 2, m / 2, m * e.L0 * e.L0 / 78, m / 2, m / 2, m * e.L0 * e.L0 / 78;
    CHECK((lumped_mass(e) - hrz).norm() <= 1e-15 * hrz.norm());
}

TEST_CASE("mass matrices carry the element mass in both directions") {
    for (double beta : {0.0, 0.9, 2.5}) {
        const Element e = make_element(beta);
        const double m = e.rhoA * e.L0;
        Vec6 tx, ty;
        tx << 1, 0, 0, 1, 0, 0;
        ty << 0, 1, 0, 0, 1, 0;
        for (const Mat6& M : {consistent_mass(e), lumped_mass(e)}) {
            CHECK(tx.dot(M * tx) == doctest::Approx(m).epsilon(1e-12));
            CHECK(ty.dot(M * ty) == doctest::Approx(m).epsilon(1e-12));
            CHECK(tx.dot(M * ty) == doctest::Approx(0.0).scale(m));
        }
    }
}

TEST_CASE("uniform load gives total force q L and the fixed-end moments q L^2 / 12") {
    const Element e = make_element(0.0, 2.0);
    const Vec6 f = uniform_load(e, Vec2(0.0, -3.0), 0.0);
    CHECK(f[1] + f[4] == doctest::Approx(-6.0));
    CHECK(f[2] == doctest::Approx(-3.0 * 4.0 / 12.0));
    CHECK(f[5] == doctest::Approx(3.0 * 4.0 / 12.0));
}

TEST_CASE("co-rotational element: free of force under large rigid motions, linear at the reference") {
    const Element e = make_element(0.3);
    Vec6 f;
    Mat6 Kt;
    for (double phi : {0.5, 2.0, 3.0, -2.8, 7.0}) {
        corotational_element(e, Vec2::Zero(), end_of(e), rigid(e, phi, Vec2(0.2, -0.4)), f, nullptr);
        CHECK(f.norm() <= 1e-9 * e.EI / e.L0);
    }
    corotational_element(e, Vec2::Zero(), end_of(e), Vec6::Zero(), f, &Kt);
    CHECK((Kt - linear_stiffness(e)).norm() <= 1e-10 * Kt.norm());
}

TEST_CASE("co-rotational tangent equals the derivative of the internal force (central differences)") {
    const Element e = make_element(0.3);
    // A strongly deformed state on top of a 1.2 rad rigid rotation.
    Vec6 d = rigid(e, 1.2, Vec2(0.05, 0.1));
    d[2] += 0.15;
    d[5] -= 0.08;
    d[3] += 0.01;
    d[4] -= 0.02;
    Vec6 f, fp, fm;
    Mat6 Kt;
    corotational_element(e, Vec2::Zero(), end_of(e), d, f, &Kt);
    Mat6 fd;
    for (int j = 0; j < 6; ++j) {
        const double h = 1e-7;
        Vec6 dp = d, dm = d;
        dp[j] += h;
        dm[j] -= h;
        corotational_element(e, Vec2::Zero(), end_of(e), dp, fp, nullptr);
        corotational_element(e, Vec2::Zero(), end_of(e), dm, fm, nullptr);
        fd.col(j) = (fp - fm) / (2 * h);
    }
    // Central differences are accurate to ~h^2 |f'''| + eps |f| / h. |Kt| is dominated by EA/L (6e9), and the
    // geometric moment term (M1 + M2)/L^2 (r z^T + z r^T) is about 1e5 here, so a bound of 1e-6 of |Kt| let a
    // 6 % error in it pass (a review, 2026-11-28). Bound: 1e-8 of |Kt|, 60 here, 0.06 % of that term (measured: 3.4e-10).
    MESSAGE("tangent against central differences: " << (Kt - fd).norm() / Kt.norm() << " of |Kt|");
    CHECK((Kt - fd).norm() <= 1e-8 * Kt.norm());
    CHECK((Kt - Kt.transpose()).norm() <= 1e-12 * Kt.norm());
}
}
