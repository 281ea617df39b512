// Rules that join sections of a scene: what the fluid's and the structure's own schemas cannot see alone.
// Each was once found only at INIT, after the participants had started (and, with --overwrite, after the
// earlier record was gone); the participants still check them, for scenes that reach them another way.
// Geometry is read from the built-in structure's keys, so these rules skip a section a custom program owns.
#include "sphfsi/coordinator/scene_cross_checks.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "sphfsi/fluid/schema.hpp"

namespace sphfsi::coordinator {
namespace {

using schema::Errors;

// A wetted member's published cross-section: the rectangle [0, L] along its axis by [-right, left] across
// it, as structure/src/interface.cpp lays out its face vertices (faces at t/2 plus the padding).
struct WettedMember {
    std::size_t index;
    double ax, ay, ex, ey, length, left, right, element;

    // Distance from (x, y) to the rectangle; 0 inside.
    double distance(double x, double y) const {
        const double s = (x - ax) * ex + (y - ay) * ey, q = -(x - ax) * ey + (y - ay) * ex;
        const double ds = std::max({0.0, -s, s - length}), dq = std::max({0.0, -right - q, q - left});
        return std::hypot(ds, dq);
    }
    // The largest distance between two vertices of one of its interface cells (the watchpoint rule's size).
    double cell_size() const { return std::hypot(element, left + right); }
    // The rectangle's four corners.
    std::vector<std::pair<double, double>> corners() const {
        const double nx = -ey, ny = ex, bx = ax + length * ex, by = ay + length * ey;
        return {{ax + left * nx, ay + left * ny}, {ax - right * nx, ay - right * ny},
                {bx + left * nx, by + left * ny}, {bx - right * nx, by - right * ny}};
    }
};

std::vector<WettedMember> wetted_members(const Value& structure) {
    std::vector<WettedMember> out;
    const double half = 0.5 * structure.at("section").at("thickness").as_double();
    const auto& members = structure.at("members").as_array();
    for (std::size_t i = 0; i < members.size(); ++i) {
        const Value& m = members[i];
        if (!m.at("wetted").as_bool()) continue;
        const auto a = m.at("start").as_doubles(), b = m.at("end").as_doubles(), pad = m.at("interface_padding").as_doubles();
        const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
        out.push_back({i, a[0], a[1], (b[0] - a[0]) / length, (b[1] - a[1]) / length, length, half + pad[0], half + pad[1],
                       length / static_cast<double>(m.at("n_elements").as_int())});
    }
    return out;
}

// The fluid fills the published cross-sections with solid particles; outside the tank and its walls they
// would be outside every wall, and the neighbour grid would grow with the distance. A periodic axis has no
// walls: there the cross-section must lie within the period (the fluid's check_inside_tank, the same rule).
void check_structure_in_tank(const Value& fluid, const std::vector<WettedMember>& wetted, Errors& e) {
    const Value& tank = fluid.at("tank");
    const double wall = static_cast<double>(tank.at("wall_layers").as_int()) * fluid.at("dp").as_double();
    const sphfsi::fluid::PeriodicAxes periodic = sphfsi::fluid::periodic_axes(fluid);
    const double x_wall = periodic.x ? 0.0 : wall, y_wall = periodic.y ? 0.0 : wall;
    const double W = tank.at("width").as_double(), H = tank.at("height").as_double();
    for (const WettedMember& m : wetted)
        for (const auto& [x, y] : m.corners())
            if (x < -x_wall || x > W + x_wall || y < -y_wall || y > H + y_wall) {
                e.add(&fluid.at("tank"), "key 'structure.members[" + std::to_string(m.index) + "]': its wetted cross-section reaches (" +
                                             schema::number_text(x) + ", " + schema::number_text(y) + ") m, outside the tank and its walls (x in [" +
                                             schema::number_text(0.0 - x_wall) + ", " + schema::number_text(W + x_wall) + "], y in [" + schema::number_text(0.0 - y_wall) + ", " +
                                             schema::number_text(H + y_wall) + "] m" + (periodic.x || periodic.y ? "; a periodic axis's period alone" : "") +
                                             "); fluid.tank and the structure's geometry disagree");
                break;
            }
}

// A watchpoint follows the nearest interface cell; farther from it than one cell size it is a typo
// (the rule coordinator/src/watchpoints.cpp applies to the mesh the structure publishes).
void check_watchpoints(const Value& points, const std::vector<WettedMember>& wetted, Errors& e) {
    std::size_t i = 0;
    for (const Value& w : points.as_array()) {
        const std::string key = "key 'watchpoint[" + std::to_string(i++) + "]'";
        if (wetted.empty()) {
            e.add(&w, key + ": watchpoints follow the wetted interface, and no structure.members[] is wetted");
            continue;
        }
        const double x = w.at("x").as_double(), y = w.at("y").as_double();
        const WettedMember* nearest = &wetted.front();
        for (const WettedMember& m : wetted)
            if (m.distance(x, y) < nearest->distance(x, y)) nearest = &m;
        if (nearest->distance(x, y) > nearest->cell_size())
            e.add(&w, key + ": (" + schema::number_text(x) + ", " + schema::number_text(y) + ") m lies " + schema::number_text(nearest->distance(x, y)) +
                          " m from the wetted structure; allowed: within one interface cell (" + schema::number_text(nearest->cell_size()) +
                          " m) of it");
    }
}

}  // namespace

void check_across_sections(const Value& scene, const std::vector<std::string>& external, Errors& e) {
    auto builtin = [&](const char* role) {
        return scene.contains(role) && std::find(external.begin(), external.end(), role) == external.end();
    };
    const bool fluid = scene.contains("fluid"), structure = scene.contains("structure");
    if (builtin("fluid") && structure && scene.at("fluid").contains("gate"))
        e.add(&scene.at("fluid").at("gate"), "key 'fluid.gate': a scene with a gate cannot also couple a structure "
                                             "(one set of solid particles per fluid); remove [fluid.gate] or [structure]");
    if (!builtin("structure")) return;
    const auto wetted = wetted_members(scene.at("structure"));
    if (fluid && wetted.empty())
        e.add(&scene.at("structure"), "key 'structure.members': a coupled scene needs at least one member with wetted = true "
                                      "(the interface the fluid acts on)");
    if (const Value* load = scene.find("load"); load && wetted.empty())
        e.add(load, "[load] is spread over the wetted interface, and no structure.members[] is wetted");
    // The structure's static solve sees its own loads; [load] reaches it with the first window. A ramp or a
    // sine is 0 at t0, so the start is in equilibrium all the same; a constant load would start it swinging.
    const Value* statics = find_path(scene, "structure.initial.static_equilibrium");
    if (const Value* load = scene.find("load");
        load && load->at("profile").as_string() == "constant" && statics && statics->as_bool()) {
        const auto f = load->at("force").as_doubles();
        if (f[0] != 0.0 || f[1] != 0.0)
            e.add(statics,
                  "key 'structure.initial.static_equilibrium': the static solve sees the structure's own loads only, and a "
                  "constant [load] is applied from the first window on, so the run would start out of equilibrium and "
                  "swing; give the load as structure.point_loads, or use load.profile = \"ramp\"");
    }
    if (const Value* points = scene.find("watchpoint")) check_watchpoints(*points, wetted, e);
    if (builtin("fluid")) check_structure_in_tank(scene.at("fluid"), wetted, e);
}

}  // namespace sphfsi::coordinator
