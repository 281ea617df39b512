// PCISPH's sums (fluid/include/sphfsi/fluid/pcisph.hpp): after a solve, each particle's pressure acceleration
// is -m / rho0^2 sum_j (p_i + p_j) W'(r_ij)/r_ij x_ij over every pair within the support at the positions of
// time t (at least one of the two particles fluid), and each fluid particle's predicted density is
// m_sum (W(0) + sum_j W(r*_ij)) at the predicted positions. The reference is the same sums taken over all
// pairs, O(N^2), with the nearest periodic image; the solver takes the first from a pair list built once per
// step (gradient_pairs.hpp) and the second from a cell search. Tolerance 1e-12 of the sums' scale: the two
// add the same terms, in different orders. Two sets: a box of jittered fluid over a wall row with two solid
// particles (dummy walls, corrected like fluid), and a doubly periodic box of jittered fluid.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/kernels.hpp"
#include "sphfsi/fluid/particles.hpp"
#include "sphfsi/fluid/pcisph.hpp"

using namespace sphfsi::fluid;

namespace {

struct Box {
    ParticleStore<2> P;
    Vec2 lo, hi;
    std::array<bool, 2> periodic{};
};

// nx x ny fluid particles at spacing dp, each moved by up to `jitter` dp, with random velocities that press them
// together and apart; with `walls`, two rows of wall particles under them and two neighbouring solid particles in
// the fluid's lowest row.
Box make_box(int nx, int ny, double dp, double jitter, bool walls, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Box b;
    std::vector<std::pair<Vec2, Kind>> parts;
    for (int i = 0; i < nx; ++i)
        for (int k = 0; k < ny; ++k)
            parts.push_back({Vec2{{(i + 0.5 + jitter * u(rng)) * dp, (k + 0.5 + jitter * u(rng)) * dp}}, Kind::Fluid});
    if (walls) {
        for (int i = 0; i < nx; ++i)
            for (int k = 1; k <= 2; ++k) parts.push_back({Vec2{{(i + 0.5) * dp, (0.5 - k) * dp}}, Kind::Wall});
        parts[static_cast<std::size_t>(ny) * 3].second = Kind::Solid;  // column 3, lowest row
        parts[static_cast<std::size_t>(ny) * 4].second = Kind::Solid;  // a solid pair, which the force leaves out
    }
    auto& P = b.P;
    P.resize(parts.size());
    for (std::size_t q = 0; q < parts.size(); ++q) {
        P.x[q] = parts[q].first;
        P.kind[q] = parts[q].second;
        P.id[q] = static_cast<std::int32_t>(q);
        P.v[q] = P.kind[q] == Kind::Fluid ? Vec2{{0.5 * u(rng), 0.5 * u(rng)}} : Vec2{};
        P.a[q] = Vec2{{0.0, -9.81}};
        P.rho[q] = 1000.0;
    }
    b.lo = Vec2{{0.0, walls ? -2.0 * dp : 0.0}};
    b.hi = Vec2{{nx * dp, ny * dp}};
    b.periodic = {!walls, !walls};
    return b;
}

// The nearest image of x_i - x_j (the period only on periodic axes).
Vec2 separation(const Box& b, const Vec2& xi, const Vec2& xj) {
    Vec2 dx = xi - xj;
    for (std::size_t d = 0; d < 2; ++d)
        if (b.periodic[d]) {
            const double L = b.hi[d] - b.lo[d];
            dx[d] -= L * std::round(dx[d] / L);
        }
    return dx;
}

void check_sums(bool walls) {
    CAPTURE(walls);
    std::mt19937 rng(walls ? 3 : 4);
    const double dp = 0.01, h = 1.3 * dp, rho0 = 1000.0, m = rho0 * dp * dp;
    Box b = make_box(16, 12, dp, 0.3, walls, rng);
    auto& P = b.P;
    const WendlandC2Kernel<2> k(h);
    CellGrid<2> grid;
    grid.configure(b.lo, b.hi, k.support(), b.periodic);
    std::vector<std::uint32_t> order;
    grid.build(P.x, order);
    std::vector<unsigned char> scratch;
    P.reorder(order, scratch);

    PcisphParams<2> prm;
    prm.mass = prm.summation_mass = m;
    prm.rho0 = rho0;
    prm.eta = 1e-4;  // tight, so that the solve corrects several times
    prm.max_iterations = 6;
    prm.clamp_negative = false;
    prm.dummy_boundaries = true;
    prm.delta_dt2 = pcisph_delta_dt2<2>(k, dp, m, m, rho0);
    PcisphScratch<2> s;
    s.resize(P.size());
    const double dt = 2e-3;
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Wall) s.x_pred[i] = P.x[i];
        else if (P.kind[i] == Kind::Solid) s.x_pred[i] = P.x[i] + Vec2{{0.0, 0.1 * dp}};
    const PcisphOutcome out = pcisph_solve(P, grid, k, k, prm, dt, s, [] {});
    REQUIRE(out.iterations >= 3);

    const double R = k.support();
    double p_max = 0.0;
    for (double p : P.p) p_max = std::max(p_max, std::abs(p));
    MESSAGE(out.iterations, " corrections, largest |p| ", p_max, " Pa, density error ", out.max_density_error);
    REQUIRE(p_max > 0.0);
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < P.size(); ++i) {
        CAPTURE(i);
        if (P.kind[i] != Kind::Wall) {
            Vec2 acc{};
            double scale = 0.0;
            for (std::size_t j = 0; j < P.size(); ++j) {
                if (j == i || (P.kind[i] != Kind::Fluid && P.kind[j] != Kind::Fluid)) continue;
                const Vec2 dx = separation(b, P.x[i], P.x[j]);
                const double r = std::sqrt(norm2(dx));
                if (r >= R) continue;
                const Vec2 term = dx * (-(P.p[i] + P.p[j]) * k.grad_factor(r) * m / (rho0 * rho0));
                acc += term;
                scale += std::sqrt(norm2(term));
                ++pairs;
            }
            CHECK(std::sqrt(norm2(s.a_p[i] - acc)) <= 1e-12 * std::max(scale, 1e-30));
        }
        if (P.kind[i] == Kind::Fluid) {
            double sum = k.w(0.0);
            for (std::size_t j = 0; j < P.size(); ++j) {
                if (j == i) continue;
                const double r = std::sqrt(norm2(separation(b, s.x_pred[i], s.x_pred[j])));
                if (r < R) sum += k.w(r);
            }
            CHECK(std::abs(s.rho_pred[i] - m * sum) <= 1e-12 * m * sum);
        }
    }
    // The list holds exactly the pairs the reference sums over.
    CHECK(s.pairs.j.size() == pairs);
    CHECK(s.pairs.shift.size() == (walls ? 0 : pairs));
}

}  // namespace

TEST_SUITE("pcisph") {
    TEST_CASE("the pressure force and the predicted densities are the sums over every pair") {
        check_sums(true);
        check_sums(false);
    }
}
