#include "sphfsi/fluid/footprint.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sphfsi/fluid/kernel_names.hpp"
#include "sphfsi/fluid/schema.hpp"

namespace sphfsi::fluid {
namespace {

double num(const sphfsi::Value& t, std::string_view k) { return t.at(k).as_double(); }

// As scene_setup's count_along: at least one particle along any length.
double along(double length, double dp) { return std::max(1.0, std::round(length / dp)); }

}  // namespace

Footprint estimate_footprint(const sphfsi::Value& fluid) {
    const sphfsi::Value& tank = fluid.at("tank");
    const double dp = num(fluid, "dp"), W = num(tank, "width"), H = num(tank, "height");
    const double layers = static_cast<double>(tank.at("wall_layers").as_int());
    const PeriodicAxes periodic = periodic_axes(fluid);
    const bool walls_x = !periodic.x, floor = !periodic.y;
    const bool lid = floor && tank.at("closed_top").as_bool();

    Footprint f;
    // Water is laid at the lattice spacing stretched to period / count along a periodic axis, obstacles at dp.
    const double sx = walls_x ? dp : W / along(W, dp), sy = floor ? dp : H / along(H, dp);
    double water_top = 0;
    if (const sphfsi::Value* boxes = fluid.find("water"))
        for (const sphfsi::Value& b : boxes->as_array()) {
            f.particles += along(num(b, "width"), sx) * along(num(b, "height"), sy);
            water_top = std::max(water_top, num(b, "y0") + num(b, "height"));
        }
    if (const sphfsi::Value* boxes = fluid.find("obstacle"))
        for (const sphfsi::Value& b : boxes->as_array()) f.particles += along(num(b, "width"), dp) * along(num(b, "height"), dp);
    const double row = along(W, dp) + (walls_x ? 2 * layers : 0);
    f.wall_particles = layers * row * ((floor ? 1 : 0) + (lid ? 1 : 0)) + (walls_x ? 2 * layers * along(H, dp) : 0);
    f.particles += f.wall_particles;
    if (fluid.find("gate")) {
        const GateBox g = gate_box(fluid);
        f.particles += along(g.thickness, dp) * along(g.height, dp);
    }

    const double support = dp * num(fluid, "h_over_dp") * kernel_support_factor(fluid.at("kernel").as_string());
    const double wall = layers * dp, head = lid ? wall : std::max(H, water_top);
    const double width = W + (walls_x ? 2 * wall : 0), height = H + (floor ? wall + head : 0);
    f.cells = std::ceil(width / support) * std::ceil(height / support);
    if (fluid.at("pressure").at("model").as_string() == "pcisph")
        f.bytes_per_particle += pair_list_bytes_per_particle(support / dp, periodic.x || periodic.y);
    return f;
}

double pair_list_bytes_per_particle(double support_over_dp, bool periodic) {
    const double pairs = std::numbers::pi * support_over_dp * support_over_dp;
    return 8.0 + (periodic ? 28.0 : 12.0) * (17.0 / 16.0) * pairs;
}

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

}  // namespace sphfsi::fluid
