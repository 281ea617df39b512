// The surface stress (wind) adds up to tau times the surface length however the surface particles are
// arranged, and the free surface is found where it meets a tank wall (surface_stress.hpp).
// Shares: a water layer periodic in x, L = 40 dp long, whose top particles are marked as the free surface
// (div r below the threshold) by hand, so only the share computation is tested; then the same layer between
// tank walls. Reference: the exact total tau L (a momentum balance). Tolerance: 1e-12 relative on the initial
// lattice, where the share is dp by construction, periodic or between walls; 1 % for the rearranged and the
// disarranged surfaces, where the share is a kernel quadrature of the surface's particle density (measured:
// 0.6 % at most). With the old rule, dp per surface particle, the compressed surface below carried 1.5 times
// the force and the doubled layer 2 times.
// Detection: a layer between walls and on a floor, its div r taken as the rate pass takes it and again with
// the tank walls mirrored; the top of every column must be found, and nothing deep.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/kernels.hpp"
#include "sphfsi/fluid/particles.hpp"
#include "sphfsi/fluid/surface_stress.hpp"

using namespace sphfsi::fluid;

namespace {

constexpr double dp = 0.01, h = 1.5 * dp, rho0 = 1000.0, mass = rho0 * dp * dp, L = 40 * dp;
const Vec2 tau{{2.0, 0.5}};  // a y part too: each share is tau times a scalar, so both totals must carry the same share
                              // (a dropped or swapped component fails; it is not an independent check of the y total)

struct Layer {
    std::vector<Vec2> x;
    std::vector<bool> surface;
    void row(double y, double spacing, double offset, bool on_surface) {
        const int n = static_cast<int>(std::lround(L / spacing));
        for (int k = 0; k < n; ++k) {
            x.push_back(Vec2{{offset + (k + 0.5) * spacing, y}});
            surface.push_back(on_surface);
        }
    }
};

// A lattice body of 8 rows under `top`'s rows; returns the total stress force on the layer, per unit tau.
double total_force(const Layer& top) {
    Layer all;
    for (int r = 0; r < 8; ++r) all.row((r + 0.5) * dp, dp, 0.0, false);
    all.x.insert(all.x.end(), top.x.begin(), top.x.end());
    all.surface.insert(all.surface.end(), top.surface.begin(), top.surface.end());
    ParticleStore<2> P;
    P.resize(all.x.size());
    for (std::size_t i = 0; i < P.size(); ++i) {
        P.x[i] = all.x[i];
        P.x[i][0] = std::fmod(P.x[i][0], L);
        P.rho[i] = rho0;
        P.kind[i] = Kind::Fluid;
        P.div_r[i] = all.surface[i] ? 1.0f : 2.0f;
    }
    CellGrid<2> grid;
    grid.configure(Vec2{{0.0, -dp}}, Vec2{{L, 12 * dp}}, 2.0 * h, {true, false});
    std::vector<std::uint32_t> order;
    grid.build(P.x, order);
    std::vector<unsigned char> scratch;
    P.reorder(order, scratch);
    apply_surface_stress(P, grid, WendlandC2Kernel<2>(h), mass, make_surface_stress<2>(tau, 1.5, h, dp));
    double fx = 0.0, fy = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i) {
        fx += P.a[i][0] * mass;
        fy += P.a[i][1] * mass;
    }
    CHECK(std::abs(fy / (tau[1] * L) - fx / (tau[0] * L)) < 1e-12);  // both parts carried alike
    return fx / (tau[0] * L);
}

// The lattice layer of total_force between two tank walls (three columns of wall particles each side, as high
// as the tank, above the water too; x in [0, L]) instead of periodic ends; the total per unit tau, with the
// walls' surface planes given to the stress or not.
double walled_total(bool planes) {
    ParticleStore<2> P;
    std::vector<Vec2> x;
    std::vector<Kind> kind;
    for (int r = 0; r < 9; ++r)
        for (int k = 0; k < 40; ++k) x.push_back(Vec2{{(k + 0.5) * dp, (r + 0.5) * dp}}), kind.push_back(Kind::Fluid);
    for (int r = 0; r < 12; ++r)
        for (int c = 0; c < 3; ++c)
            for (const double at : {-(c + 0.5) * dp, L + (c + 0.5) * dp})
                x.push_back(Vec2{{at, (r + 0.5) * dp}}), kind.push_back(Kind::Wall);
    P.resize(x.size());
    for (std::size_t i = 0; i < P.size(); ++i) {
        P.x[i] = x[i];
        P.rho[i] = rho0;
        P.kind[i] = kind[i];
        P.div_r[i] = kind[i] == Kind::Fluid && x[i][1] > 8 * dp ? 1.0f : 2.0f;  // the top fluid row
    }
    CellGrid<2> grid;
    grid.configure(Vec2{{-4 * dp, -dp}}, Vec2{{L + 4 * dp, 13 * dp}}, 2.0 * h, {false, false});
    std::vector<std::uint32_t> order;
    grid.build(P.x, order);
    std::vector<unsigned char> scratch;
    P.reorder(order, scratch);
    std::vector<WallPlane> walls;
    if (planes) walls = {{0, 0.0, 1}, {0, L, -1}, {1, 0.0, 1}};
    const double carried =
        apply_surface_stress(P, grid, WendlandC2Kernel<2>(h), mass, make_surface_stress<2>(tau, 1.5, h, dp, walls));
    double fx = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid) fx += P.a[i][0] * mass;
    CHECK(std::abs(carried * tau[0] / fx - 1.0) < 1e-12);  // the surface it reports is the one the force acted on
    return fx / (tau[0] * L);
}

// A layer 9 rows deep in a tank (three columns of wall particles each side, as high as 12 rows, above the
// water too, and three rows of floor), every fluid particle moved by up to `jitter` dp each way (seeded), as a
// developed flow disarranges the lattice. div r is first taken as the rate pass takes it, every neighbour
// counted, walls included (an O(N^2) sum here), then again at the tank walls by detect_surface_at_tank_walls.
struct WalledLayer {
    static constexpr int columns = 40, rows = 9;
    ParticleStore<2> P;
    CellGrid<2> grid;
    std::vector<float> raw_div_r;  // by fluid index k * rows + r (column k, row r), before the tank-wall pass
    std::vector<std::uint32_t> where;  // the same fluid index -> its place in P after the sort
    std::vector<WallPlane> walls{{0, 0.0, 1}, {0, L, -1}, {1, 0.0, 1}};

    // An obstacle: columns 18 - 20 are wall particles standing on the floor, 12 rows high, instead of water.
    static bool in_obstacle(int k) { return k >= 18 && k <= 20; }

    WalledLayer(double jitter, unsigned seed, bool obstacle = false) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-jitter * dp, jitter * dp);
        std::vector<Vec2> x;
        std::vector<Kind> kind;
        for (int k = 0; k < columns; ++k)
            for (int r = 0; r < rows; ++r)
                x.push_back(Vec2{{(k + 0.5) * dp + u(rng), (r + 0.5) * dp + u(rng)}}),
                    kind.push_back(obstacle && in_obstacle(k) ? Kind::Wall : Kind::Fluid);
        if (obstacle)
            for (int k = 0; k < columns; ++k)
                for (int r = rows; r < 12 && in_obstacle(k); ++r)
                    x.push_back(Vec2{{(k + 0.5) * dp, (r + 0.5) * dp}}), kind.push_back(Kind::Wall);
        for (int r = -3; r < 12; ++r)
            for (int c = 0; c < 3; ++c)
                for (const double at : {-(c + 0.5) * dp, L + (c + 0.5) * dp})
                    x.push_back(Vec2{{at, (r + 0.5) * dp}}), kind.push_back(Kind::Wall);
        for (int r = 1; r <= 3; ++r)
            for (int k = 0; k < columns; ++k)
                x.push_back(Vec2{{(k + 0.5) * dp, -(r - 0.5) * dp}}), kind.push_back(Kind::Wall);
        const WendlandC2Kernel<2> kg(h);
        const double R = kg.support();
        P.resize(x.size());
        for (std::size_t i = 0; i < P.size(); ++i) {
            P.x[i] = x[i];
            P.rho[i] = rho0;
            P.kind[i] = kind[i];
            P.id[i] = static_cast<std::int32_t>(i);
            double div_r = 0.0;
            for (std::size_t j = 0; j < x.size(); ++j) {
                const double r = std::sqrt(norm2(x[i] - x[j]));
                if (j != i && r < R) div_r -= kg.grad_factor(r) * r * r / rho0;
            }
            P.div_r[i] = static_cast<float>(mass * div_r);
        }
        raw_div_r.assign(P.div_r.begin(), P.div_r.begin() + columns * rows);
        grid.configure(Vec2{{-4 * dp, -4 * dp}}, Vec2{{L + 4 * dp, 13 * dp}}, R, {false, false});
        std::vector<std::uint32_t> order;
        grid.build(P.x, order);
        std::vector<unsigned char> scratch;
        P.reorder(order, scratch);
        where.resize(columns * rows);
        for (std::size_t i = 0; i < P.size(); ++i)
            if (P.id[i] < columns * rows) where[static_cast<std::size_t>(P.id[i])] = static_cast<std::uint32_t>(i);
        detect_surface_at_tank_walls(P, grid, kg, mass, make_surface_stress<2>(tau, 1.5, h, dp, walls));
    }
    float div_r(int k, int r) const { return P.div_r[where[static_cast<std::size_t>(k * rows + r)]]; }
    float raw(int k, int r) const { return raw_div_r[static_cast<std::size_t>(k * rows + r)]; }
};

}  // namespace

TEST_SUITE("wind") {
    // Where the surface meets a tank wall, the rate pass's div r counts the dry wall particles above the water
    // as fluid: 1.496 at the corner of the resting lattice against the 1.5 threshold, so a disarranged surface
    // loses its corner particles (a review, 2026-11-28). With the tank walls mirrored (ghost fluid, as Marrone
    // et al. 2010 detect the surface) every column's top particle must be found, next to the walls too, and no
    // particle below the top two rows, the floor's corners included. Reference: the layer's own geometry (the
    // top of every column is on the surface; the floor and the walls below the water are not a surface).
    TEST_CASE("the free surface is found where it meets the tank walls") {
        const WalledLayer resting(0.0, 1);
        const int top = WalledLayer::rows - 1, last = WalledLayer::columns - 1;
        std::printf("div r at the surface's ends, resting lattice: %.4f and %.4f (the rate pass's %.4f and %.4f), "
                    "mid-surface %.4f, bottom corner %.4f (rate pass %.4f), bulk %.4f\n",
                    resting.div_r(0, top), resting.div_r(last, top), resting.raw(0, top), resting.raw(last, top),
                    resting.div_r(20, top), resting.div_r(0, 0), resting.raw(0, 0), resting.div_r(20, 4));
        // On the resting lattice the images stand where the wall particles stand, except the dry ones.
        for (const int end : {0, last}) {
            CHECK(std::abs(resting.div_r(end, 0) - resting.raw(end, 0)) < 1e-5f);
            CHECK(std::abs(resting.div_r(end, top) - resting.div_r(20, top)) < 1e-5f);
        }
        int ends_missed_before = 0;
        double worst_total = 0.0;
        for (unsigned seed = 1; seed <= 8; ++seed) {
            WalledLayer layer(0.1, seed);
            const double carried = apply_surface_stress(layer.P, layer.grid, WendlandC2Kernel<2>(h), mass,
                                                        make_surface_stress<2>(tau, 1.5, h, dp, layer.walls));
            worst_total = std::max(worst_total, std::abs(carried / L - 1.0));
            for (int k = 0; k < WalledLayer::columns; ++k) {
                CHECK_MESSAGE(layer.div_r(k, top) < 1.5f, "seed ", seed, ", column ", k, ": top particle not found");
                for (int r = 0; r < top - 1; ++r)
                    CHECK_MESSAGE(layer.div_r(k, r) >= 1.5f, "seed ", seed, ", column ", k, ", row ", r, " found");
            }
            ends_missed_before += (layer.raw(0, top) >= 1.5f) + (layer.raw(last, top) >= 1.5f);
        }
        // What stands in the water is mirrored with it: an obstacle on the floor has its image below the floor,
        // as the wall particles under it were, so on the resting lattice every particle below the top two rows
        // keeps the rate pass's div r, the obstacle's foot included (mirroring the fluid alone left a hole
        // there: div r 0.254 lower beside the obstacle's foot, 0.046 one column further).
        const WalledLayer blocked(0.0, 1, true);
        for (int k = 0; k < WalledLayer::columns; ++k)
            for (int r = 0; r < top - 1 && !WalledLayer::in_obstacle(k); ++r)
                CHECK_MESSAGE(std::abs(blocked.div_r(k, r) - blocked.raw(k, r)) < 1e-5f, "column ", k, ", row ", r);
        std::printf("surface ends the rate pass's div r missed, 8 disarranged layers: %d of 16; their surfaces "
                    "carry the wind on L (1 +- %.4f)\n", ends_missed_before, worst_total);
        CHECK(ends_missed_before > 0);  // the layers do test what the tank-wall pass mends
        // The shares of a disarranged surface are a kernel quadrature: 1 %, as for the rearranged surfaces of
        // the next test (measured 0.51 % at worst over these eight layers).
        CHECK(worst_total < 0.01);
    }

    TEST_CASE("the surface stress adds up to tau times the surface length however the surface is arranged") {
        Layer lattice;
        lattice.row(8.5 * dp, dp, 0.0, true);
        const double on_lattice = total_force(lattice);

        Layer compressed;  // 1.5 surface particles per dp, as a sheared surface layer packs them
        compressed.row(8.5 * dp, dp / 1.5, 0.0, true);
        const double packed = total_force(compressed);

        Layer doubled;  // the top two rows both flagged, one above the other
        doubled.row(8.5 * dp, dp, 0.0, true);
        doubled.row(9.5 * dp, dp, 0.0, true);
        const double two_rows = total_force(doubled);

        Layer staggered;  // the second row half a spacing along, 0.4 dp higher
        staggered.row(8.5 * dp, dp, 0.0, true);
        staggered.row(8.9 * dp, dp, 0.5 * dp, true);
        const double offset_rows = total_force(staggered);

        std::printf("surface stress, total / (tau L): lattice %.6f, 1.5 per dp %.6f, two rows %.6f, staggered %.6f\n",
                    on_lattice, packed, two_rows, offset_rows);
        CHECK(std::abs(on_lattice - 1.0) < 1e-12);
        // Between tank walls the surface ends. Without the walls' images the particles next to them counted
        // neighbours on one side only (a review, 2026-11-27: the wind basin's total was 0.4012 m for 0.4 m).
        // With them, and with the normals taken over the same mirrored neighbours (until 2026-11-29 the end
        // particles' normals leaned away from the wall rising above the water and the total was 0.9972), the
        // lattice's surface is exact again: tolerance 1e-12 as on the periodic lattice.
        const double walled = walled_total(true), unmirrored = walled_total(false);
        std::printf("surface stress between walls, total / (tau L): %.14f (without the wall images %.6f)\n", walled,
                    unmirrored);
        CHECK(std::abs(walled - 1.0) < 1e-12);
        CHECK(std::abs(unmirrored - 1.0) > 0.01);
        CHECK(std::abs(packed - 1.0) < 0.01);
        CHECK(std::abs(two_rows - 1.0) < 0.01);
        CHECK(std::abs(offset_rows - 1.0) < 0.01);
    }
}
