#include "sphfsi/fluid/scene_setup.hpp"

#include <algorithm>
#include <cmath>

namespace sphfsi::fluid {
namespace {

int count_along(double length, double dp) { return std::max(1, static_cast<int>(std::lround(length / dp))); }

struct Builder {
    Scene2D& scene;
    void add(double x, double y, Kind kind, int tag, Vec2 velocity = {}) {
        auto& P = scene.particles;
        P.x.push_back(Vec2{{x, y}});
        P.v.push_back(velocity);
        P.rho.push_back(0.0);
        P.id.push_back(static_cast<std::int32_t>(P.x.size() - 1));
        P.tag.push_back(tag);
        P.kind.push_back(kind);
    }
    // Fills [x0, x0 + nx*sx] x [y0, y0 + ny*sy] with particles at cell centres.
    void fill(double x0, double y0, int nx, int ny, double sx, double sy, Kind kind, int tag, Vec2 velocity = {}) {
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) add(x0 + (i + 0.5) * sx, y0 + (j + 0.5) * sy, kind, tag, velocity);
    }
};

}  // namespace

Scene2D build_scene(const FluidSettings& s) {
    Scene2D scene;
    Builder b{scene};
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
                b.add(w.box.x0 + (i + 0.5) * sx, w.box.y0 + (j + 0.5) * sy, Kind::Fluid, tag);
                scene.column_top.push_back(top);
            }
    }
    scene.n_fluid = scene.particles.size();

    const bool walls_x = !s.periodic[0], floor = !s.periodic[1], lid = s.closed_top && !s.periodic[1];
    const int nx_in = count_along(W, sx), ny_in = count_along(H, sy);
    const double x_lo = walls_x ? -T : 0.0;
    const int nx_out = nx_in + (walls_x ? 2 * L : 0);
    const int wall_tag = -1;
    if (floor) b.fill(x_lo, -T, nx_out, L, sx, dp, Kind::Wall, wall_tag);
    if (walls_x) {
        b.fill(-T, 0.0, L, ny_in, dp, sy, Kind::Wall, wall_tag);
        b.fill(W, 0.0, L, ny_in, dp, sy, Kind::Wall, wall_tag);
    }
    if (lid) b.fill(x_lo, H, nx_out, L, sx, dp, Kind::Wall, wall_tag, Vec2{{s.lid_velocity[0], s.lid_velocity[1]}});
    for (const auto& o : s.obstacles)
        b.fill(o.x0, o.y0, count_along(o.width, dp), count_along(o.height, dp), o.width / count_along(o.width, dp),
               o.height / count_along(o.height, dp), Kind::Wall, wall_tag);
    scene.n_wall = scene.particles.size() - scene.n_fluid;
    scene.particles.resize(scene.particles.x.size());

    scene.geometry = WallGeometry{W, H, T, walls_x, floor, lid, s.obstacles};
    // Grid region: the tank with its walls, plus head room above an open tank for splashes (particles
    // beyond it are still found, in the border cells).
    scene.domain_lo = Vec2{{walls_x ? -T : 0.0, floor ? -T : 0.0}};
    const double head = lid ? T : std::max(H, s.water_top());
    scene.domain_hi = Vec2{{walls_x ? W + T : W, floor ? H + head : H}};
    return scene;
}

}  // namespace sphfsi::fluid
