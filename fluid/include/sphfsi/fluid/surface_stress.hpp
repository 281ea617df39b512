#pragma once
// A shear stress applied to the free surface (wind, from the shallow-lake paper): each free-surface fluid
// particle carries the stress on the piece of surface it represents, so the total force is tau times the
// surface length (area in 3D), however the surface layer is arranged (to the share's quadrature accuracy),
// as long as every surface particle is flagged. A lone flagged particle (no normal) takes a whole lattice
// share, about 2 dp.
//
// Which particles: the rate pass flags a fluid particle whose divergence of position (div r, every neighbour
// counted, walls included) is below the threshold. Where the surface meets a tank wall, that count is wrong:
// the dry wall particles above the water count as fluid would (1.496 against the 1.5 threshold on the initial
// lattice), so once the surface tilts the particle at the wall is often not flagged, and the shares added up
// to 0.979 - 0.996 of the length in the developed wind basin (dp = 4 and 2 mm; a review, 2026-11-28). So
// within reach of a tank wall the detection is taken again with that wall as the ghost-fluid method has it
// (Marrone et al. 2010 detect the surface this way): its particles left out, the mirror images of the fluid
// (and of whatever stands in it) across its surface put in. Below the water the images stand where the wall
// particles stand (a wall's layers start dp/2 behind its surface, as the fluid's rows start dp/2 in front),
// so nothing changes there; above it there is no fluid to mirror, so a dry wall no longer looks like water.
// The surface normal is taken over the same neighbours, which keeps the end particles' normals from leaning
// away from the wall rising above the water (on the resting lattice between walls the shares then add up to
// the length exactly, where they had come to 0.9972 of it). Obstacles and coupled structures have no surface
// plane of their own and keep their particles. Measured (docs/validation.md, wind basin): the developed
// basin's shares now add up to 0.99 - 1.00 of the length at dp = 4 mm; at 2 and 1.33 mm 0.98 - 0.99 and
// 0.978, the rest lost in the disordered surface layer (pairs of surface particles with gaps between them,
// where the shares' quadrature is not exact, and a few particles under them not flagged).
//
// Which piece. On the initial lattice every surface particle represents dp^(Dim-1) of surface, and that is
// all the first version assumed. A surface under a sustained stress does not stay a lattice: in a closed
// basin the surface current converges on the lee shore and diverges on the windward one, and the top layers
// rearrange. Measured (wind-driven closed basin 0.4 m long, 40 mm deep, dp = 2 mm, tau = 5 Pa,
// scenarios/wind_basin.toml): the free-surface particles grew from 200 to 252 by t = 5 s (120 over the
// middle 100 dp, 1.36 per dp in places), and with tau dp each the wind's force grew with them. With the
// shares below, the same run had 259 surface particles at t = 5 s whose shares add up to 0.390 m of the
// 0.4 m surface (0.400 m at t = 0; before the wall images below, 0.4012 m: a review, 2026-11-27).
//
// So a surface particle's share is measured, not assumed: 1 / (the number of surface particles per unit
// surface around it), the number density taken along the surface, i.e. with the neighbours' offsets
// projected onto the tangent plane, so that two surface particles one above the other share one piece. The
// density is a kernel sum in Dim - 1 dimensions (the Wendland C2 profile), divided by the same sum on the
// initial lattice: the share is exactly dp^(Dim-1) there, and the profile's normalising constant cancels.
// The outward normal is the direction of minus the colour gradient, -sum_j grad W_ij over every neighbour,
// walls and solids included (so a wall is not a surface), a tank wall within reach as its mirrored fluid.
//
// Where the surface meets a tank wall it ends, and its last particles would count surface neighbours on one
// side only: on the initial lattice the particle next to a wall took 1.29 dp and the next one 1.02 dp (the
// basin's total 0.4012 m for 0.4 m; a review, 2026-11-27). The density sum therefore adds the mirror images,
// across each tank wall's surface plane, of the surface particles near it (the particle itself included), as
// if the surface went on beyond the wall: exactly dp on the lattice again. Only across a wall the surface
// meets, one whose normal lies within 45 degrees of the surface's tangent: a thin layer running along the
// floor has the floor below it, not at its end, and images there would halve its shares. Obstacles and
// coupled structures piercing the surface get no images.
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

// A tank wall's surface: the plane where coordinate `axis` is `at`, the water on the side `inward` (+1 or -1)
// points to. All three are given: a default side would silently put a right wall or a lid the wrong way.
// The plane is taken as unbounded; a side wall of an open tank ends at the tank's top, and water thrown
// above it would be mirrored across a wall that is not there (no scene puts wind on such water).
struct WallPlane {
    int axis;
    double at;
    int inward;
    WallPlane(int axis_, double at_, int inward_) : axis(axis_), at(at_), inward(inward_) {
        if (inward != 1 && inward != -1) throw std::invalid_argument("WallPlane: inward must be +1 or -1");
    }
    bool behind(double coordinate) const { return (coordinate - at) * inward < 0.0; }
    // Whether a point is within `reach` of the plane (on either side).
    template <class V>
    bool within(const V& x, double reach) const { return std::abs(x[static_cast<std::size_t>(axis)] - at) < reach; }
};

template <int Dim>
struct SurfaceStress {
    Vec<Dim> tau{};                // stress [Pa]
    float threshold = 0.75f * Dim; // divergence of position below which a fluid particle is on the surface
    double h = 0.0;                // smoothing length: the surface weight reaches 2h
    double lattice_share = 0.0;    // dp^(Dim-1) times the surface weight summed over the initial lattice
    std::vector<WallPlane> walls;  // the tank's wall surfaces (mirror images of the surface near them)
    bool on() const { return norm2(tau) > 0.0; }
};

// The Wendland C2 profile (1 - q/2)^4 (2q + 1), q = r / h, without its normalising constant.
inline double surface_weight(double q) {
    if (q >= 2.0) return 0.0;
    const double t = 1.0 - 0.5 * q, t2 = t * t;
    return t2 * t2 * (2.0 * q + 1.0);
}

// dp^(Dim-1) times the sum of the surface weight over a flat surface lattice of spacing dp (Dim - 1
// dimensions), the particle itself included.
template <int Dim>
SurfaceStress<Dim> make_surface_stress(const Vec<Dim>& tau, double threshold, double h, double dp,
                                       std::vector<WallPlane> walls = {}) {
    SurfaceStress<Dim> s;
    s.tau = tau;
    s.walls = std::move(walls);
    s.threshold = static_cast<float>(threshold);
    s.h = h;
    const int n = static_cast<int>(std::ceil(2.0 * h / dp));
    double sum = 0.0;
    for (int a = -n; a <= n; ++a) {
        if constexpr (Dim == 2) {
            sum += surface_weight(std::abs(a) * dp / h);
        } else {
            for (int b = -n; b <= n; ++b) sum += surface_weight(std::hypot(a, b) * dp / h);
        }
    }
    s.lattice_share = std::pow(dp, Dim - 1) * sum;
    return s;
}

// Calls visit(dx, r2, j) for each neighbour of fluid particle i within the kernel's reach (dx = x_i - x_j,
// 0 < r2 < R2), as the detection and the normal see them: a tank wall within reach of x_i is left out and
// everything kept is mirrored across its surface instead, the fluid and whatever stands in it (an obstacle or
// a structure on the floor has its image below the floor as the water beside it has; i's own images
// included; across two walls at a corner, the image of an image). An image is never nearer than what it
// mirrors (x_i and x_j on the water's side), so the cells searched for x_i hold every image within reach.
// Opposite walls both within reach of one particle (a tank under two supports wide) would need images of
// images along one axis; those are left out.
template <int Dim, class Visit>
void for_each_mirrored_neighbour(const ParticleStore<Dim>& P, const typename CellGrid<Dim>::Range* ranges, int nr,
                                 std::uint32_t i, const std::vector<WallPlane>& walls, double R2, Visit&& visit) {
    using V = Vec<Dim>;
    constexpr int max_near = 2 * Dim;
    const V xi = P.x[i];
    const double R = std::sqrt(R2);
    const WallPlane* near[max_near];
    int nw = 0;
    for (const WallPlane& w : walls)
        if (nw < max_near && w.within(xi, R)) near[nw++] = &w;
    const auto behind_a_near_wall = [&](const V& x) {
        for (int q = 0; q < nw; ++q)
            if (near[q]->behind(x[static_cast<std::size_t>(near[q]->axis)])) return true;
        return false;
    };
    const auto visit_if_within = [&](const V& dx, std::uint32_t j) {
        const double r2 = norm2(dx);
        if (r2 < R2 && r2 > 0.0) visit(dx, r2, j);
    };
    for (int r = 0; r < nr; ++r)
        for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
            const V xj = P.x[j] + ranges[r].shift;
            if (P.kind[j] == Kind::Wall && behind_a_near_wall(xj)) continue;
            visit_if_within(xi - xj, j);
            for (int set = 1; set < (1 << nw); ++set) {  // each non-empty set of near walls, mirrored in turn
                V image = xj;
                int axes = 0;
                bool repeated_axis = false;
                for (int q = 0; q < nw; ++q) {
                    if (!(set & (1 << q))) continue;
                    const auto k = static_cast<std::size_t>(near[q]->axis);
                    repeated_axis |= (axes >> k) & 1;
                    axes |= 1 << k;
                    image[k] = 2.0 * near[q]->at - image[k];
                }
                if (!repeated_axis) visit_if_within(xi - image, j);
            }
        }
}

// Takes div r again, with the tank walls mirrored (above), for every fluid particle within reach of a tank
// wall (of those with only[i] != 0 when `only` is given), after the rate pass has written P.div_r: the wind's
// and the record's free-surface flags and the kernel correction's mask then read this value. Its form is the
// rate pass's, m sum_j (V_j / m_j) r_ij F(r_ij) r_ij, an image with the volume of the particle it mirrors.
// The simulation runs it in scenes with wind only (simulation_rates.cpp says why); in the others the
// record's flag is the rate pass's, which can miss a particle where the surface meets a tank wall, and a
// one- or two-particle film along the floor.
template <int Dim, class KernelG>
void detect_surface_at_tank_walls(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelG& kg, double mass,
                                  const SurfaceStress<Dim>& s, const std::uint8_t* only = nullptr) {
    if (s.walls.empty()) return;
    const double R2 = grid.radius2(), R = std::sqrt(R2);
    const auto near_a_wall = [&](std::uint32_t i) {
        for (const WallPlane& w : s.walls)
            if (w.within(P.x[i], R)) return true;
        return false;
    };
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        int nr = -1;
        for (std::uint32_t i = begin; i < end; ++i) {
            if (P.kind[i] != Kind::Fluid || (only && !only[i]) || !near_a_wall(i)) continue;
            if (nr < 0) nr = grid.ranges(cell, ranges);
            double div_r = 0.0;
            for_each_mirrored_neighbour(P, ranges, nr, i, s.walls, R2,
                                        [&](const Vec<Dim>&, double r2, std::uint32_t j) {
                                            div_r -= kg.grad_factor(std::sqrt(r2)) * r2 / P.rho[j];
                                        });
            P.div_r[i] = static_cast<float>(mass * div_r);
        }
    });
}

// Adds the stress to the acceleration of every free-surface fluid particle (of those with only[i] != 0 when
// `only` is given). Reads P.div_r, which the rate pass has just written for every fluid particle. Returns the
// surface those particles carry, the sum of their shares (m in 2D): tau times it is the stress's total force,
// tau times the surface's length when every surface particle is found. Summed per cell, then over the cells in
// order, so the figure does not depend on the thread count.
template <int Dim, class KernelG>
double apply_surface_stress(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelG& kg, double mass,
                            const SurfaceStress<Dim>& s, const std::uint8_t* only = nullptr) {
    using V = Vec<Dim>;
    const double R2 = grid.radius2(), reach2 = 4.0 * s.h * s.h, inv_h = 1.0 / s.h;
    const auto on_surface = [&](std::uint32_t j) { return P.kind[j] == Kind::Fluid && P.div_r[j] < s.threshold; };
    std::vector<double> carried(grid.cell_count(), 0.0);
    grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
        typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
        int nr = -1;
        for (std::uint32_t i = begin; i < end; ++i) {
            if ((only && !only[i]) || !on_surface(i)) continue;
            if (nr < 0) nr = grid.ranges(cell, ranges);
            const V xi = P.x[i];
            V normal{};
            for_each_mirrored_neighbour(P, ranges, nr, i, s.walls, R2, [&](const V& dx, double r2, std::uint32_t) {
                normal -= dx * kg.grad_factor(std::sqrt(r2));
            });
            const double n2 = norm2(normal);
            const V unit = n2 > 0.0 ? normal * (1.0 / std::sqrt(n2)) : V{};  // none: a lone particle
            double density = 0.0;
            auto count = [&](const V& xj) {  // a surface particle (or image) at xj
                const V dx = xi - xj;
                if (norm2(dx) >= reach2) return;
                const V along = dx - unit * dot(dx, unit);
                density += surface_weight(std::sqrt(norm2(along)) * inv_h);
            };
            // Its images across the walls within reach of xi (only those can be within reach).
            auto count_with_images = [&](const V& xj) {
                count(xj);
                for (const WallPlane& w : s.walls) {
                    const auto k = static_cast<std::size_t>(w.axis);
                    if (!w.within(xi, 2.0 * s.h) || std::abs(unit[k]) > std::sqrt(0.5)) continue;
                    V image = xj;
                    image[k] = 2.0 * w.at - xj[k];
                    count(image);
                }
            };
            count_with_images(xi);
            for (int r = 0; r < nr; ++r)
                for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j)
                    if (j != i && on_surface(j)) count_with_images(P.x[j] + ranges[r].shift);
            P.a[i] += s.tau * (s.lattice_share / (density * mass));
            carried[cell] += s.lattice_share / density;
        }
    });
    double total = 0.0;
    for (const double c : carried) total += c;
    return total;
}

}  // namespace sphfsi::fluid
