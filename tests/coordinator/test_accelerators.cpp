// The implicit schemes' update rules (accelerators.hpp) on affine maps, where their behaviour is known
// exactly: the structure's answer to an interface displacement d is H(d) = (A d + b, C d + e), displacement
// then velocity, and the fixed point solves A d + b = d.
//   * Aitken on one unknown is the secant method: exact at its second update (round-off: 1e-12 relative).
//   * IQN-ILS on n unknowns: its least squares holds the exact inverse Jacobian once it has n independent
//     secant pairs, so it lands on the fixed point at its (n + 1)-th update (Degroote, Bathe & Vierendeels
//     2009, its equivalence to GMRES for linear problems), or one later when the QR2 filter drops a pair
//     within 1 % of dependent on the newer ones (measured here: the 6th); a next window of the same map
//     (another b) starts from the kept pairs and lands at its first update. The velocity is updated with the
//     same combination, so it ends at C d* + e.
//   * A history handed to a new accelerator (as a resumed run's, read from its checkpoint) gives the same
//     iterates bit for bit.
// Before 2026-11-27 these classes were inside implicit.cpp and tested only through whole coupled runs (a review).
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "sphfsi/coordinator/accelerators.hpp"

using namespace sphfsi::coordinator;
using Vec = Eigen::VectorXd;

namespace {

struct AffineStructure {
    Eigen::MatrixXd A, C;
    Vec b, e;
    Vec answer(const Vec& x) const {  // x: displacement then velocity; the answer depends on the displacement
        const auto n = A.rows();
        Vec out(2 * n);
        out << A * x.head(n) + b, C * x.head(n) + e;
        return out;
    }
    Vec fixed_point() const {
        const auto n = A.rows();
        const Vec d = (Eigen::MatrixXd::Identity(n, n) - A).lu().solve(b);
        Vec out(2 * n);
        out << d, C * d + e;
        return out;
    }
};

// Iterates one window as ImplicitScheme does, from the answer to d = 0 (a pair the structure can answer
// with, as the predictors' are); returns the number of structure answers it took to reach
// |d~ - d| <= 1e-12 |d*| (at most `cap`), and the final iterate in `x`.
int window(Accelerator& acc, SecantHistory& history, const AffineStructure& s, Vec& x, int cap) {
    const auto n = s.A.rows();
    x = s.answer(Vec::Zero(2 * n));
    acc.begin_window(history);
    const double scale = s.fixed_point().head(n).norm();
    for (int k = 1; k <= cap; ++k) {
        const Vec xt = s.answer(x);
        if ((xt.head(n) - x.head(n)).norm() <= 1e-12 * scale) {
            acc.end_window(true);
            return k;
        }
        x = acc.next(x, xt, n);
    }
    acc.end_window(false);
    return cap + 1;
}

AffineStructure four_unknowns() {
    AffineStructure s;
    s.A.resize(4, 4);
    // Eigenvalues beyond 1 in modulus: plain fixed-point iteration diverges on it, as on a light structure
    // under heavy water.
    s.A << 0.5, 1.2, 0.0, 0.3,  //
        -0.4, 0.8, 0.6, 0.0,    //
        0.2, 0.0, -1.5, 0.7,    //
        0.1, 0.3, 0.2, 0.9;
    s.C = 2.0 * Eigen::MatrixXd::Identity(4, 4) + 0.1 * s.A;
    s.b = Vec::LinSpaced(4, 1.0, 4.0);
    s.e = Vec::Constant(4, -0.5);
    return s;
}

}  // namespace

TEST_SUITE("accelerators") {
    TEST_CASE("Aitken on one unknown is the secant method: exact at its second update") {
        AffineStructure s;
        s.A = Eigen::MatrixXd::Constant(1, 1, -3.0);  // fixed-point iteration alone diverges (|a| > 1)
        s.C = Eigen::MatrixXd::Constant(1, 1, 0.7);
        s.b = Vec::Constant(1, 2.0);
        s.e = Vec::Constant(1, 0.1);
        Aitken acc(0.1);
        SecantHistory none;
        Vec x;
        // Answers: at x0 = 0, at x1 (relaxed by 0.1), at x2 (the secant's root, the fixed point).
        CHECK(window(acc, none, s, x, 10) == 3);
        const Vec exact = s.fixed_point();
        CHECK((x - exact).norm() <= 1e-12 * exact.norm());
        CHECK(none.empty());
    }

    TEST_CASE("an Aitken factor of exactly zero starts again from the scene's factor") {
        // Residuals r0 = (1, 0) and r1 = (1, 1): r0 . (r1 - r0) = 0 gives the factor 0, which would freeze the
        // iterate at x1 and every later residual difference at 0 until max_iterations (a review, 2026-11-27).
        Aitken acc(0.1);
        SecantHistory history;
        acc.begin_window(history);
        Vec x0 = Vec::Zero(4), xt0(4);
        xt0 << 1.0, 0.0, 0.0, 0.0;
        const Vec x1 = acc.next(x0, xt0, 2);
        CHECK(x1[0] == doctest::Approx(0.1));
        Vec xt1 = x1;
        xt1[0] += 1.0;
        xt1[1] += 1.0;
        const Vec x2 = acc.next(x1, xt1, 2);
        CHECK(x2[0] == doctest::Approx(x1[0] + 0.1));  // moved on with the scene's factor, not frozen at x1
        CHECK(x2[1] == doctest::Approx(x1[1] + 0.1));
    }

    TEST_CASE("IQN-ILS lands on an affine map's fixed point within n + 1 updates, and at once from kept pairs") {
        const AffineStructure s = four_unknowns();
        IqnIls acc(0.1, 8);
        SecantHistory history;
        Vec x;
        const int answers = window(acc, history, s, x, 20);
        MESSAGE("IQN-ILS, 4 unknowns: " << answers << " answers");
        CHECK(answers <= 4 + 3);  // n + 1 updates (n + 2 with a pair filtered), then the answer that shows it
        const Vec exact = s.fixed_point();
        CHECK((x - exact).norm() <= 1e-10 * exact.norm());  // velocity included
        REQUIRE(history.size() == 1);
        CHECK(history.front().V.size() == static_cast<std::size_t>(answers - 2));  // the last pair is not kept
        // A second window, another load: the kept pairs hold the whole Jacobian.
        AffineStructure t = s;
        t.b = Vec::LinSpaced(4, -2.0, 1.0);
        CHECK(window(acc, history, t, x, 20) == 2);
        CHECK((x - t.fixed_point()).norm() <= 1e-10 * t.fixed_point().norm());
        // Without the kept pairs it takes the full count again.
        IqnIls fresh(0.1, 0);
        SecantHistory unused;
        CHECK(window(fresh, unused, t, x, 20) > 2);
        CHECK(unused.empty());
    }

    TEST_CASE("a history handed to a new IQN-ILS, as a resumed run's, gives the same iterates bit for bit") {
        const AffineStructure s = four_unknowns();
        AffineStructure t = s;
        t.b = Vec::LinSpaced(4, 0.5, -1.0);
        t.A(0, 0) = 0.6;  // not the same map: the kept pairs are an approximation, used with new ones
        IqnIls running(0.1, 8);
        SecantHistory history;
        Vec x;
        REQUIRE(window(running, history, s, x, 20) < 20);  // converged, so that it kept pairs to hand over
        REQUIRE(!history.empty());
        SecantHistory copy = history;  // what the checkpoint holds
        Vec x_running, x_resumed;
        const int a = window(running, history, t, x_running, 20);
        IqnIls resumed(0.1, 8);
        const int b = window(resumed, copy, t, x_resumed, 20);
        CHECK(a == b);
        CHECK(x_running == x_resumed);
        REQUIRE(history.size() == copy.size());
        CHECK(history.front().V == copy.front().V);
    }

    TEST_CASE("a window stopped at its cap keeps no pairs; at most iqn_reuse windows are kept") {
        const AffineStructure s = four_unknowns();
        IqnIls acc(0.1, 2);
        SecantHistory history;
        Vec x;
        CHECK(window(acc, history, s, x, 2) == 3);  // capped: not converged
        CHECK(history.empty());
        // Each window a different map, so that the kept pairs never hold its Jacobian and every window
        // iterates and keeps pairs (with one map, later windows land at once and keep none: a review found the
        // cap then untested).
        for (int w = 0; w < 4; ++w) {
            AffineStructure t = s;
            t.A += 0.3 * (w + 1) * Eigen::MatrixXd::Identity(4, 4);
            t.b = Vec::Constant(4, 1.0 + w);
            CHECK(window(acc, history, t, x, 20) > 3);
            CHECK(history.size() == static_cast<std::size_t>(std::min(w + 1, 2)));
        }
    }
}
