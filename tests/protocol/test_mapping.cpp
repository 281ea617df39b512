// Interface mapping: interpolation is consistent (reproduces linear fields) and spreading is
// conservative (total force and moment preserved to round-off).
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "sphfsi/protocol/mapping.hpp"

using namespace sphfsi::protocol;

namespace {
// A distorted strip of 3 quads, like a bent beam's cross-section.
InterfaceMesh strip() {
    F64Array v({8, 2}, {0, 0, 1, 0.1, 2, 0.3, 3, 0.7, 0, 0.5, 1.05, 0.6, 2.1, 0.75, 3.2, 1.3});
    I32Array c({3, 4}, {0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6});
    return {v, c};
}
}  // namespace

TEST_CASE("points are located in their cell with weights that reproduce their position") {
    InterfaceMesh m = strip();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 200; ++k) {
        int c = k % 3;
        // a random point inside cell c: bilinear combination of its corners
        double a = u(rng), b = u(rng);
        auto corner = [&](int i) { return std::array<double, 2>{m.vertices(m.cells(c, i), 0), m.vertices(m.cells(c, i), 1)}; };
        double w[4] = {(1 - a) * (1 - b), a * (1 - b), a * b, (1 - a) * b};
        double x = 0, y = 0;
        for (int i = 0; i < 4; ++i) {
            x += w[i] * corner(i)[0];
            y += w[i] * corner(i)[1];
        }
        MappedPoint p = locate(m, x, y);
        CHECK(p.distance < 1e-12);
        auto back = interpolate(p, m.vertices);  // interpolating the positions gives the point back
        CHECK(back[0] == doctest::Approx(x).epsilon(1e-12));
        CHECK(back[1] == doctest::Approx(y).epsilon(1e-12));
        double sum = p.weight[0] + p.weight[1] + p.weight[2] + p.weight[3];
        CHECK(sum == doctest::Approx(1.0).epsilon(1e-14));
    }
}

TEST_CASE("a point far from a cell far away is located in it, at a distance that says how far") {
    // A structure whose cell sits at 1e300 m: Newton's inverse map overflowed to NaN, no distance compared
    // below infinity, and a watchpoint was told "the structure publishes no interface cells" (a review,
    // 2026-11-28). The nearest cell is found; the distance is at least the real one (or infinite).
    for (const double far : {1e300, 1.7e308}) {
        CAPTURE(far);
        InterfaceMesh m{F64Array({4, 2}, {far, far, far + far * 1e-3, far, far + far * 1e-3, far + far * 1e-3, far, far + far * 1e-3}),
                        I32Array({1, 4}, {0, 1, 2, 3})};
        const MappedPoint p = locate(m, 0.0, 0.0);
        CHECK(p.cell == 0);
        CHECK(p.distance >= far);
        CHECK_FALSE(std::isnan(p.distance));
    }
}

TEST_CASE("spreading point forces preserves total force and moment in the deformed configuration") {
    InterfaceMesh m = strip();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    // deformed vertex positions: reference plus an arbitrary displacement
    F64Array disp = F64Array::zeros(8, 2);
    for (auto& d : disp.values) d = 0.2 * u(rng);
    F64Array current = m.vertices;
    for (std::size_t i = 0; i < current.values.size(); ++i) current.values[i] += disp.values[i];

    F64Array vf = F64Array::zeros(8, 2);
    double fx = 0, fy = 0, moment = 0;
    for (int k = 0; k < 500; ++k) {
        MappedPoint p = locate(m, 3.0 * (0.5 + 0.5 * u(rng)), 0.3 + 0.2 * u(rng));
        auto pos = interpolate(p, current);  // the particle sits where the deformed cell puts it
        std::array<double, 2> f{u(rng), u(rng)};
        spread(p, f, vf);
        fx += f[0];
        fy += f[1];
        moment += pos[0] * f[1] - pos[1] * f[0];
    }
    double vx = 0, vy = 0, vm = 0;
    for (int i = 0; i < 8; ++i) {
        vx += vf(i, 0);
        vy += vf(i, 1);
        vm += current(i, 0) * vf(i, 1) - current(i, 1) * vf(i, 0);
    }
    CHECK(std::abs(vx - fx) < 1e-12);
    CHECK(std::abs(vy - fy) < 1e-12);
    CHECK(std::abs(vm - moment) < 1e-11);
}
