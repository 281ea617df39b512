#include "sphfsi/fluid/scene_setup.hpp"

#include <algorithm>
#include <cmath>

#include "sphfsi/fluid/gate.hpp"

namespace sphfsi::fluid {
namespace {

int count_along(double length, double dp) { return std::max(1, static_cast<int>(std::lround(length / dp))); }

// Calls emit(position, velocity, kind, tag, column_top) for every particle of the scene in id order: water
// blocks (column_top: the top of the particle's block), then tank walls and obstacles (column_top unused).
template <class Emit>
void lay_out(const FluidSettings& s, Emit&& emit) {
    const double dp = s.dp, W = s.tank_width, H = s.tank_height;
    const int L = s.wall_layers;
    const double T = L * dp;
    // Along a periodic axis the lattice spacing is stretched to period / count so the seam is seamless.
    const double sx = s.periodic[0] ? W / count_along(W, dp) : dp;
    const double sy = s.periodic[1] ? H / count_along(H, dp) : dp;

    for (const auto& w : s.water) {
        const int nx = count_along(w.box.width, sx), ny = count_along(w.box.height, sy);
        const double top = w.box.y0 + ny * sy;
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                int tag = w.tag;
                if (w.split == DyeSplit::Vertical && 2 * i >= nx) tag = w.tag + 1;
                if (w.split == DyeSplit::Horizontal && 2 * j >= ny) tag = w.tag + 1;
                emit(Vec2{{w.box.x0 + (i + 0.5) * sx, w.box.y0 + (j + 0.5) * sy}}, Vec2{}, Kind::Fluid, tag, top);
            }
    }

    // Fills [x0, x0 + nx*sx] x [y0, y0 + ny*sy] with wall particles at cell centres.
    const int wall_tag = -1;
    auto fill = [&](double x0, double y0, int nx, int ny, double fx, double fy, Vec2 velocity = {}) {
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                emit(Vec2{{x0 + (i + 0.5) * fx, y0 + (j + 0.5) * fy}}, velocity, Kind::Wall, wall_tag, 0.0);
    };
    const bool walls_x = !s.periodic[0], floor = !s.periodic[1], lid = s.closed_top && !s.periodic[1];
    const int nx_in = count_along(W, sx), ny_in = count_along(H, sy);
    const double x_lo = walls_x ? -T : 0.0;
    const int nx_out = nx_in + (walls_x ? 2 * L : 0);
    if (floor) fill(x_lo, -T, nx_out, L, sx, dp);
    if (walls_x) {
        fill(-T, 0.0, L, ny_in, dp, sy);
        fill(W, 0.0, L, ny_in, dp, sy);
    }
    if (lid) fill(x_lo, H, nx_out, L, sx, dp, Vec2{{s.lid_velocity[0], s.lid_velocity[1]}});
    for (const auto& o : s.obstacles)
        fill(o.x0, o.y0, count_along(o.width, dp), count_along(o.height, dp), o.width / count_along(o.width, dp),
             o.height / count_along(o.height, dp));
}

}  // namespace

Scene2D build_scene(const FluidSettings& s) {
    Scene2D scene;
    // Counted first, then filled: every array is allocated once at its final size (grown by push_back, each
    // would keep up to half again as much unused capacity for the whole run).
    std::size_t n = 0;
    lay_out(s, [&](const Vec2&, const Vec2&, Kind kind, int, double) {
        ++n;
        scene.n_fluid += kind == Kind::Fluid;
    });
    auto& P = scene.particles;
    P.resize(n);
    scene.column_top.resize(scene.n_fluid);
    std::size_t i = 0;
    lay_out(s, [&](const Vec2& x, const Vec2& v, Kind kind, int tag, double column_top) {
        P.x[i] = x;
        P.v[i] = v;
        P.rho[i] = 0.0;
        P.id[i] = static_cast<std::int32_t>(i);
        P.tag[i] = tag;
        P.kind[i] = kind;
        if (kind == Kind::Fluid) scene.column_top[i] = column_top;
        ++i;
    });
    scene.n_wall = n - scene.n_fluid;

    const double dp = s.dp, W = s.tank_width, H = s.tank_height, T = s.wall_layers * dp;
    const bool walls_x = !s.periodic[0], floor = !s.periodic[1], lid = s.closed_top && !s.periodic[1];
    scene.geometry = WallGeometry{W, H, T, walls_x, floor, lid, s.obstacles};
    // Grid region: the tank with its walls, plus head room above an open tank for splashes (particles
    // beyond it are still found, in the border cells).
    scene.domain_lo = Vec2{{walls_x ? -T : 0.0, floor ? -T : 0.0}};
    const double head = lid ? T : std::max(H, s.water_top());
    scene.domain_hi = Vec2{{walls_x ? W + T : W, floor ? H + head : H}};
    return scene;
}

std::vector<Vec2> gate_particles(const FluidSettings& s) {
    std::vector<Vec2> out;
    if (!s.gate) return out;
    const Gate& g = *s.gate;
    const int nx = count_along(g.thickness, s.dp), ny = count_along(g.height, s.dp);
    const double fx = g.thickness / nx, fy = g.height / ny;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) out.push_back(Vec2{{g.x0 + (i + 0.5) * fx, (j + 0.5) * fy}});
    return out;
}

bool inside_tank(const WallGeometry& g, const Vec2& p) {
    const double tol = 1e-9 * std::max(g.width, g.height);
    return (!g.walls_x || (p[0] > tol && p[0] < g.width - tol)) && (!g.floor || p[1] > tol) &&
           (!g.lid || p[1] < g.height - tol);
}

}  // namespace sphfsi::fluid
