// Simulation2D: failure checks after every step (non-finite values, density bounds, speed, a particle lost
// through a wall), which stop the run naming the step, time, particle and quantity, and the validation
// count of wall crossings.
#include "sphfsi/fluid/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "format.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {

using protocol::SolverError;

std::string Simulation2D::particle_named(std::size_t i) const {
    const V& x = st_.P.x[i];
    return "particle " + std::to_string(st_.P.id[i]) + " at (" + fmt(x[0]) + ", " + fmt(x[1]) + ") m";
}

// Every failure names the particle the same way, by its id and (while it has one) its position, so that a
// density, a speed or a wall crossing can each be found in the last frame.
void Simulation2D::fail(std::size_t i, const std::string& quantity, double value, const std::string& why) const {
    const std::string who = all_finite(st_.P.x[i]) ? particle_named(i) : "particle " + std::to_string(st_.P.id[i]);
    throw SolverError("diverged", "step " + std::to_string(st_.step + (stepping_ ? 1 : 0)) + ", t = " + fmt(st_.t) + " s: " + who +
                                      ": " + quantity + " = " + fmt(value) + " (" + why + ")");
}

// Over the top of a side wall of an open tank and out beyond its outer face: the particle has left the tank
// (a splash, or water spilling over the brim), which is physics, not a failure. "Over the top" allows the
// centre to be up to the wall's thickness below the wall's top when it passes the outer face: water spilling
// slowly over a brim rides the top with its centre at about the top surface and drops as soon as it rounds the
// outer corner (the brim-full tank of tests/fluid/test_failure.cpp put a spilling particle's centre 0.13 mm
// below the top at dp = 2.5 mm, and that used to stop the run as "lost through the wall"; so did a brim-full
// wind-driven basin). A particle that went through the wall lower down is still a failure (check_state).
// A tank periodic in y has side walls over the whole period and no brim: nothing leaves it over a wall.
bool Simulation2D::over_the_wall(const V& x) const {
    const auto& g = geometry_;
    return g.walls_x && g.floor && !g.lid && x[1] > g.height - g.thickness &&
           (x[0] < -g.thickness || x[0] > g.width + g.thickness);
}

void Simulation2D::mark_escaped() {
    // Escaped particles are frozen and leave the computation.
    const auto& g = geometry_;
    if (!g.walls_x || !g.floor || g.lid) return;
    auto& P = st_.P;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        if (over_the_wall(P.x[i])) {
            P.kind[i] = Kind::Escaped;
            P.v[i] = V{};
            P.a[i] = V{};
            P.drho[i] = 0.0;
            ++st_.escaped;
        }
    }
}

// Deeper inside a static obstacle than its wall layers reach from a face the water can touch: lost through
// it, like a particle beyond a tank wall's outer face. Each axis has its own depth: along a side thinner than
// two wall layers, no centre gets that deep, so there it is within half a spacing of the box's middle, and at
// least half a spacing past the face (a step moves a particle a small fraction of a spacing, so one passing
// through lands in that band; without the repulsive force centres sit up to 0.43 dp past a surface). A side
// no thicker than dp has no such band: across_obstacle_middle catches water through it. A face on a tank wall
// is not one the water can touch: a box standing on the floor counts from its others.
bool Simulation2D::through_obstacle(const Box& b, const V& x) const {
    const auto& g = geometry_;
    const double tol = 1e-9 * std::max(g.width, g.height);
    auto depth = [&](double side) { return std::min(g.thickness, std::max(0.5 * (side - s_.dp), 0.5 * s_.dp)); };
    const double dx = depth(b.width), dy = depth(b.height);
    const double inf = std::numeric_limits<double>::infinity();
    const double x_lo = g.walls_x && b.x0 <= tol ? -inf : b.x0 + dx;
    const double x_hi = g.walls_x && b.x0 + b.width >= g.width - tol ? inf : b.x0 + b.width - dx;
    const double y_lo = g.floor && b.y0 <= tol ? -inf : b.y0 + dy;
    const double y_hi = g.lid && b.y0 + b.height >= g.height - tol ? inf : b.y0 + b.height - dy;
    // The open sides extend the box only as far as the wall beside it: beyond, the tank's own checks apply.
    const bool inside_x = x[0] > x_lo && x[0] < x_hi && x[0] > -g.thickness && x[0] < g.width + g.thickness;
    const bool inside_y = x[1] > y_lo && x[1] < y_hi && x[1] > -g.thickness && x[1] < g.height + g.thickness;
    return inside_x && inside_y;
}

// A step whose path crosses a box's middle line more than dp/2 inside the box's other two faces (or anywhere
// along a side against a tank wall): the particle is past the middle from whichever face it came through, where
// the box's own wall particles sit. Water is never there, so this stops nothing the depth rule lets through on
// a thick box, and it catches water through a side no thicker than dp, which has no depth band at all (a
// review, 2026-11-27). The path is the step's: from x - dt v to x (exact for symplectic Euler, within
// dt^2 |a| / 2 for the other integrators, a small fraction of dp).
bool Simulation2D::across_obstacle_middle(const Box& b, const V& from, const V& to) const {
    const auto& g = geometry_;
    const double tol = 1e-9 * std::max(g.width, g.height), inf = std::numeric_limits<double>::infinity();
    const double lo[2] = {b.x0, b.y0}, size[2] = {b.width, b.height};
    // Where the water can reach along each axis: dp/2 inside a face it can touch, the wall itself beyond an
    // open side (the tank's own checks take over there).
    const double reach_lo[2] = {g.walls_x && b.x0 <= tol ? -inf : b.x0 + 0.5 * s_.dp,
                                g.floor && b.y0 <= tol ? -inf : b.y0 + 0.5 * s_.dp};
    const double reach_hi[2] = {g.walls_x && b.x0 + b.width >= g.width - tol ? inf : b.x0 + b.width - 0.5 * s_.dp,
                                g.lid && b.y0 + b.height >= g.height - tol ? inf : b.y0 + b.height - 0.5 * s_.dp};
    for (int axis = 0; axis < 2; ++axis) {
        const double middle = lo[axis] + 0.5 * size[axis];
        const double a = from[axis] - middle, c = to[axis] - middle;
        if ((a < 0.0) == (c < 0.0)) continue;
        const int other = 1 - axis;
        const double at = from[other] + a / (a - c) * (to[other] - from[other]);  // where the path crosses it
        if (at > reach_lo[other] && at < reach_hi[other]) return true;
    }
    return false;
}

bool Simulation2D::density_in_bounds(double rho) const {
    return rho >= s_.min_density_ratio * s_.rho0 && rho <= s_.max_density_ratio * s_.rho0;  // false for NaN
}

void Simulation2D::fail_density(std::size_t i) const {
    const double rho = st_.P.rho[i], lo = s_.min_density_ratio * s_.rho0, hi = s_.max_density_ratio * s_.rho0;
    if (!std::isfinite(rho)) fail(i, "density", rho, "not finite");
    if (rho < lo) fail(i, "density", rho, "below min_density_ratio * rho0 = " + fmt(lo) + " kg/m^3");
    fail(i, "density", rho, "above max_density_ratio * rho0 = " + fmt(hi) + " kg/m^3");
}

void Simulation2D::check_summed_densities() const {
    const auto& P = st_.P;
    const long long n = static_cast<long long>(P.size());
    bool bad = false;
#pragma omp parallel for schedule(static) reduction(|| : bad)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        bad = bad || (P.kind[i] == Kind::Fluid && !density_in_bounds(P.rho[i]));
    }
    if (!bad) return;
    std::size_t worst = P.size();  // the lowest id, as check_state names it
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid && !density_in_bounds(P.rho[i]) && (worst == P.size() || P.id[i] < P.id[worst]))
            worst = i;
    fail_density(worst);
}

Simulation2D::StepCheck Simulation2D::check_state(double dt) {
    mark_escaped();
    if (section_.on()) section_.place(st_.t, dt);
    const auto& P = st_.P;
    const auto& g = geometry_;
    const double v_cap = s_.max_mach * c0_;  // 0: no reference speed (PCISPH without gravity or u_max)
    bool bad = false;
    double rho_max = 0.0;
    std::size_t crossings = 0;
    const double surface_tol = crossing_tolerance * s_.dp;
    const long long n = static_cast<long long>(P.size());
    auto broken = [&](std::size_t i) {
        const V& x = P.x[i];
        if (!all_finite(x) || !all_finite(P.v[i]) || !density_in_bounds(P.rho[i])) return true;
        if (v_cap > 0.0 && dot(P.v[i], P.v[i]) > v_cap * v_cap) return true;
        // mark_escaped has taken every particle that left over a side wall; beyond one now is through it.
        if (g.walls_x && (x[0] < -g.thickness || x[0] > g.width + g.thickness)) return true;
        if (g.floor && x[1] < -g.thickness) return true;
        if (g.lid && x[1] > g.height + g.thickness) return true;
        for (const Box& b : g.obstacles)
            if (through_obstacle(b, x) || across_obstacle_middle(b, x - dt * P.v[i], x)) return true;
        return section_.on() && (section_.lost(x) || section_.crossed_middle(x - dt * P.v[i], x));
    };
#pragma omp parallel for schedule(static) reduction(|| : bad) reduction(max : rho_max) reduction(+ : crossings)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] != Kind::Fluid) continue;
        bad = bad || broken(i);
        rho_max = std::max(rho_max, P.rho[i]);
        crossings += beyond_wall_surface(P.x[i], surface_tol) != Beyond::Nothing;
    }
    if (!bad) return {rho_max, crossings};
    // Name the first offender (lowest id), with the quantity and why.
    std::size_t worst = P.size();
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid && broken(i) && (worst == P.size() || P.id[i] < P.id[worst])) worst = i;
    const std::size_t i = worst;
    const V& x = P.x[i];
    if (!all_finite(x)) fail(i, "position", std::isfinite(x[0]) ? x[1] : x[0], "not finite");
    if (!all_finite(P.v[i])) fail(i, "velocity", norm(P.v[i]), "not finite");
    if (!density_in_bounds(P.rho[i])) fail_density(i);
    if (v_cap > 0.0 && dot(P.v[i], P.v[i]) > v_cap * v_cap)
        fail(i, "speed", norm(P.v[i]), "above max_mach * c0 = " + fmt(v_cap) + " m/s");
    if (g.walls_x && x[0] < -g.thickness) fail(i, "x", x[0], "beyond the outer face of the left wall at x = " + fmt(-g.thickness) + " m: lost through the wall");
    if (g.walls_x && x[0] > g.width + g.thickness) fail(i, "x", x[0], "beyond the outer face of the right wall at x = " + fmt(g.width + g.thickness) + " m: lost through the wall");
    if (g.floor && x[1] < -g.thickness) fail(i, "y", x[1], "below the outer face of the floor at y = " + fmt(-g.thickness) + " m: lost through the wall");
    if (g.lid && x[1] > g.height + g.thickness) fail(i, "y", x[1], "above the outer face of the lid at y = " + fmt(g.height + g.thickness) + " m: lost through the wall");
    if (section_.on() && section_.lost(x))
        fail(i, "x", x[0], "inside " + section_.name() + ", deeper than the wall layers (" + fmt(g.thickness) +
                               " m) below every face the water can touch, or across a thin part within dp/2 of its middle: "
                               "lost through it");
    if (section_.on() && section_.crossed_middle(x - dt * P.v[i], x))
        fail(i, "x", x[0], "its step crossed the middle of " + section_.name() + " where it is one cell thick: lost through it");
    for (const Box& b : g.obstacles) {
        const std::string box = "the obstacle x in [" + fmt(b.x0) + ", " + fmt(b.x0 + b.width) + "], y in [" + fmt(b.y0) +
                                ", " + fmt(b.y0 + b.height) + "] m";
        if (through_obstacle(b, x))
            fail(i, "x", x[0], "inside " + box + ", deeper than its wall layers (at most " + fmt(g.thickness) +
                                   " m) below every face the water can touch: lost through it");
        if (across_obstacle_middle(b, x - dt * P.v[i], x))
            fail(i, "x", x[0], "its step crossed the middle of " + box + ": lost through it");
    }
    fail(i, "x", x[0], "lost through a wall");  // not reached: broken(i) held for one of the above
}

Simulation2D::Beyond Simulation2D::beyond_wall_surface(const V& x, double tol) const {
    const auto& g = geometry_;
    const bool beside_walls = g.lid || x[1] <= g.height;
    if (g.walls_x && beside_walls && x[0] < -tol) return Beyond::LeftWall;
    if (g.walls_x && beside_walls && x[0] > g.width + tol) return Beyond::RightWall;
    if (g.floor && x[1] < -tol) return Beyond::Floor;
    if (g.lid && x[1] > g.height + tol) return Beyond::Lid;
    for (const Box& b : g.obstacles)
        if (x[0] > b.x0 + tol && x[0] < b.x0 + b.width - tol && x[1] > b.y0 + tol && x[1] < b.y0 + b.height - tol)
            return Beyond::Obstacle;
    if (section_.on() && section_.past_surface(x, tol)) return Beyond::Section;
    return Beyond::Nothing;
}

Simulation2D::Crossing Simulation2D::wall_crossings() const {
    Crossing c;
    const auto& P = st_.P;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        const Beyond where = beyond_wall_surface(P.x[i], crossing_tolerance * s_.dp);
        if (where == Beyond::Nothing || c.count++ > 0) continue;
        const std::string why = where == Beyond::LeftWall    ? "left of the left wall surface"
                                : where == Beyond::RightWall ? "right of the right wall surface"
                                : where == Beyond::Floor     ? "below the floor surface"
                                : where == Beyond::Lid       ? "above the lid surface"
                                : where == Beyond::Obstacle  ? "inside an obstacle"
                                                             : "inside " + section_.name();
        c.first = particle_named(i) + ": " + why;
    }
    return c;
}

}  // namespace sphfsi::fluid
