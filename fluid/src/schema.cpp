// The [fluid] scene section. Units are SI; 2D quantities are per metre of depth.
#include "sphfsi/fluid/schema.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "format.hpp"
#include "sphfsi/fluid/footprint.hpp"
#include "sphfsi/fluid/grid_limits.hpp"
#include "sphfsi/fluid/kernel_names.hpp"

namespace sphfsi::fluid {
namespace {

using sphfsi::Value;
using sphfsi::schema::Errors;
using sphfsi::schema::TableSchema;

std::string key(const std::string& path, const std::string& name) { return path.empty() ? name : path + "." + name; }

double num(const Value& t, std::string_view k) { return t.at(k).as_double(); }

// Walls thicker than this are a typo: the widest support allowed, the Gaussian's 3 h at h_over_dp = 8/3, fits.
constexpr int kMaxWallLayers = 8;

// Small slack so that a block written as 0.1 m wide in a 0.1 m tank is not rejected by rounding.
constexpr double slack = 1e-9;

// Whether [a0, a1] and [b0, b1] share more than the slack (touching is not overlapping).
bool spans_overlap(double a0, double a1, double b0, double b1) { return a0 < b1 - slack && b0 < a1 - slack; }

void check_boxes_inside_tank(const Value& fluid, const std::string& path, Errors& errors) {
    const Value& tank = fluid.at("tank");
    const double W = num(tank, "width"), H = num(tank, "height"), dp = num(fluid, "dp");
    for (const char* list : {"water", "obstacle"}) {
        const Value* blocks = fluid.find(list);
        if (!blocks) continue;
        std::size_t i = 0;
        for (const Value& b : blocks->as_array()) {
            const std::string where = key(path, std::string(list) + "[" + std::to_string(i++) + "]");
            const double x0 = num(b, "x0"), y0 = num(b, "y0"), w = num(b, "width"), h = num(b, "height");
            if (x0 < -slack || y0 < -slack || x0 + w > W + slack || y0 + h > H + slack)
                errors.add(&b, "key '" + where + "': the box [" + schema::number_text(x0) + ", " + schema::number_text(x0 + w) +
                                   "] x [" + schema::number_text(y0) + ", " + schema::number_text(y0 + h) +
                                   "] m does not lie inside the tank [0, " + schema::number_text(W) + "] x [0, " +
                                   schema::number_text(H) + "] m");
            if (w < dp * (1 - 1e-9) || h < dp * (1 - 1e-9))
                errors.add(&b, "key '" + where + "': the box is thinner than one particle spacing dp = " + fmt(dp) + " m");
        }
    }
    if (W < dp * (1 - 1e-9) || H < dp * (1 - 1e-9))
        errors.add(&fluid.at("dp"), "key '" + key(path, "dp") + "': " + fmt(dp) + " m is more than the tank's " +
                                        (W < H ? "width" : "height") + " (" + fmt(std::min(W, H)) +
                                        " m); allowed: at most the tank's smaller side");
    const Value* water = fluid.find("water");
    if (!water) return;
    auto boxes_overlap = [](const Value& a, const Value& b) {
        return spans_overlap(num(a, "x0"), num(a, "x0") + num(a, "width"), num(b, "x0"), num(b, "x0") + num(b, "width")) &&
               spans_overlap(num(a, "y0"), num(a, "y0") + num(a, "height"), num(b, "y0"), num(b, "y0") + num(b, "height"));
    };
    const auto& blocks = water->as_array();
    for (std::size_t i = 0; i < blocks.size(); ++i) {
        // Two blocks over the same space would lay particles on top of each other: twice the mass there.
        for (std::size_t j = 0; j < i; ++j)
            if (boxes_overlap(blocks[i], blocks[j]))
                errors.add(&blocks[i], "key '" + key(path, "water[" + std::to_string(i) + "]") + "': overlaps water[" +
                                           std::to_string(j) + "]; blocks of water must not share space");
        if (const Value* obstacles = fluid.find("obstacle")) {
            std::size_t j = 0;
            for (const Value& o : obstacles->as_array()) {
                if (boxes_overlap(blocks[i], o))
                    errors.add(&blocks[i], "key '" + key(path, "water[" + std::to_string(i) + "]") + "': overlaps obstacle[" +
                                               std::to_string(j) + "]; water and static walls must not share space");
                ++j;
            }
        }
    }
}

// The gate stands on the floor inside the tank, beside the water, and rises through an open top.
void check_gate(const Value& fluid, const std::string& path, Errors& errors) {
    const Value* gate = fluid.find("gate");
    if (!gate) return;
    const Value& tank = fluid.at("tank");
    const double W = num(tank, "width"), H = num(tank, "height"), dp = num(fluid, "dp");
    const auto [x0, t, h] = gate_box(fluid);
    if (x0 < -slack || x0 + t > W + slack)
        errors.add(gate, "key '" + key(path, "gate.x0") + "': the gate [" + schema::number_text(x0) + ", " + schema::number_text(x0 + t) +
                             "] m does not lie inside the tank [0, " + schema::number_text(W) + "] m");
    if (h > H + slack)
        errors.add(gate, "key '" + key(path, "gate.height") + "': higher than the tank (" + schema::number_text(H) + " m)");
    if (t < dp * (1 - 1e-9))
        errors.add(gate, "key '" + key(path, "gate.thickness") + "': thinner than one particle spacing dp = " + schema::number_text(dp) + " m");
    if (tank.at("closed_top").as_bool() || periodic_axes(fluid).y)
        errors.add(gate, "key '" + key(path, "gate") + "': the gate stands on the floor and rises out through an open top; "
                                                        "it needs tank.closed_top = false and no periodic y axis");
    for (const char* list : {"water", "obstacle"}) {
        const Value* boxes = fluid.find(list);
        if (!boxes) continue;
        std::size_t i = 0;
        for (const Value& b : boxes->as_array()) {
            if (spans_overlap(num(b, "x0"), num(b, "x0") + num(b, "width"), x0, x0 + t) &&
                spans_overlap(num(b, "y0"), num(b, "y0") + num(b, "height"), 0.0, h))
                errors.add(gate, "key '" + key(path, "gate") + "': overlaps " + list + "[" + std::to_string(i) + "]");
            ++i;
        }
    }
}

void check_combinations(const Value& fluid, const std::string& path, Errors& errors) {
    const Value& pressure = fluid.at("pressure");
    const Value& density = fluid.at("density");
    const Value& time = fluid.at("time");
    const Value& tank = fluid.at("tank");
    const std::string model = pressure.at("model").as_string();
    const std::string method = density.at("method").as_string();
    if (model == "pcisph" && time.at("integrator").as_string() != "symplectic_euler")
        errors.add(&time, "key '" + key(path, "time.integrator") +
                              "': PCISPH is its own predictor-corrector around a semi-implicit Euler step; allowed with "
                              "pressure.model = \"pcisph\": \"symplectic_euler\"");
    if (model == "pcisph" && method == "continuity")
        errors.add(&density, "key '" + key(path, "density.method") +
                                 "': PCISPH predicts densities by summation; allowed with pressure.model = \"pcisph\": "
                                 "\"summation\", \"shepard\"");
    if (model == "pcisph" && pressure.at("min_iterations").as_int() > pressure.at("max_iterations").as_int())
        errors.add(&pressure, "key '" + key(path, "pressure.min_iterations") + "': " +
                                  std::to_string(pressure.at("min_iterations").as_int()) + " is more than pressure.max_iterations (" +
                                  std::to_string(pressure.at("max_iterations").as_int()) +
                                  "); allowed: at most pressure.max_iterations");
    if (model == "pcisph" && pressure.at("kernel_correction").as_bool())
        errors.add(&pressure, "key '" + key(path, "pressure.kernel_correction") +
                                  "': corrects the pressure term of standard SPH and WCSPH; PCISPH's pressure force is its own; "
                                  "allowed with pressure.model = \"pcisph\": false");
    if (density.at("reinitialise_every").as_int() != 0 && method != "continuity")
        errors.add(&density, "key '" + key(path, "density.reinitialise_every") +
                                 "': re-initialises integrated densities; it needs density.method = \"continuity\" "
                                 "(allowed otherwise: 0)");
    if (density.at("diffusion").as_string() != "none" && method != "continuity")
        errors.add(&density, "key '" + key(path, "density.diffusion") +
                                 "': density diffusion (delta-SPH) is a term of the continuity equation; it needs "
                                 "density.method = \"continuity\"");
    const Value& visc = fluid.at("viscosity");
    const std::string vm = visc.at("model").as_string();
    if ((vm == "morris" || vm == "mueller") && !(visc.at("nu").as_double() > 0.0))
        errors.add(&visc, "key '" + key(path, "viscosity.nu") + "': the \"" + vm + "\" viscosity needs nu > 0");
    const auto lid = tank.at("lid_velocity").as_doubles();
    if ((lid[0] != 0.0 || lid[1] != 0.0) && !tank.at("closed_top").as_bool())
        errors.add(&tank, "key '" + key(path, "tank.lid_velocity") + "': a moving lid needs tank.closed_top = true");
    if (lid[1] != 0.0)
        errors.add(&tank, "key '" + key(path, "tank.lid_velocity") + "': the lid slides in its own plane; its y component must be 0");
    const PeriodicAxes periodic = periodic_axes(fluid);
    const double support = num(fluid, "dp") * num(fluid, "h_over_dp") * kernel_support_factor(fluid.at("kernel").as_string());
    // The grid's own rule (grid_limits.hpp): a length of exactly 3 supports holds only 2 of its cells, which
    // are a hair wider than the support, and was once accepted here and refused at INIT as an internal error.
    for (const auto& [wraps, length] : {std::pair<bool, const char*>{periodic.x, "width"}, {periodic.y, "height"}})
        if (wraps && periodic_cells(num(tank, length), support) < 3)
            errors.add(&tank, "key '" + key(path, std::string("tank.") + length) + "': " + fmt(num(tank, length)) +
                                  " m; a periodic axis must be longer than 3 kernel support radii (3 x " + fmt(support) +
                                  " m = " + fmt(3.0 * support) + " m)");
    // A fluid particle by a wall must find wall particles over its whole support, or its kernel sums are
    // cut there (the Gaussian's 3 h at h = 1.5 dp reaches 4.5 dp, past the default 3 layers).
    const auto layers = tank.at("wall_layers").as_int();
    const auto needed = static_cast<long long>(std::ceil(support / num(fluid, "dp") - 1e-9));
    const bool walled = !(periodic.x && periodic.y);
    if (walled && needed > kMaxWallLayers)
        errors.add(&fluid.at("h_over_dp"), "key '" + key(path, "h_over_dp") + "': the support radius (" + schema::number_text(support) +
                                               " m) needs " + std::to_string(needed) + " wall layers, more than the " +
                                               std::to_string(kMaxWallLayers) + " allowed; allowed with kernel \"" +
                                               fluid.at("kernel").as_string() + "\": h_over_dp <= " +
                                               std::to_string(kMaxWallLayers / kernel_support_factor(fluid.at("kernel").as_string())));
    else if (walled && static_cast<double>(layers) * num(fluid, "dp") < support * (1.0 - 1e-9))
        errors.add(&tank, "key '" + key(path, "tank.wall_layers") + "': " + std::to_string(layers) +
                              " layers of dp are thinner than the kernel's support radius (" + schema::number_text(support) +
                              " m); allowed: at least " + std::to_string(needed));
    if (periodic.y && tank.at("closed_top").as_bool())
        errors.add(&tank, "key '" + key(path, "tank.closed_top") + "': a tank periodic in y has no bottom or top wall");
    // WCSPH's equation of state needs c0; so does artificial viscosity (alpha c0) with PCISPH, which would
    // otherwise run with none, silently (a review).
    const Value& viscosity = fluid.at("viscosity");
    const bool needs_c0 = model == "wcsph" || (model == "pcisph" && viscosity.at("model").as_string() == "artificial" &&
                                               viscosity.at("alpha").as_double() > 0.0);
    if (needs_c0 && pressure.at("c0").as_double() == 0.0 && pressure.at("u_max").as_double() == 0.0) {
        const auto g = fluid.at("gravity").as_doubles();
        const Value* water = fluid.find("water");
        if (std::hypot(g[0], g[1]) == 0.0 || !water || water->as_array().empty())
            errors.add(&pressure, "key '" + key(path, "pressure.c0") + "': c0 cannot be estimated without gravity and water" +
                                      (model == "pcisph" ? " (artificial viscosity scales with it)" : "") +
                                      "; set pressure.c0 or pressure.u_max");
    }
    // The repulsive force's default strength is 5 |g| H: without gravity or water it is 0, and the force,
    // turned on, silently does nothing (a review found a test relying on it that way).
    const Value& boundary = fluid.at("boundary");
    if (boundary.at("repulsive").as_bool() && num(boundary, "repulsive_d") == 0.0) {
        const auto g = fluid.at("gravity").as_doubles();
        const Value* water = fluid.find("water");
        if (std::hypot(g[0], g[1]) == 0.0 || !water || water->as_array().empty())
            errors.add(&boundary, "key '" + key(path, "boundary.repulsive_d") + "': the repulsive force's default "
                                      "strength 5 |g| H is 0 without gravity and water; set boundary.repulsive_d > 0 "
                                      "(m^2/s^2) or turn boundary.repulsive off");
    }
    const Value& failure = fluid.at("failure");
    if (num(failure, "min_density_ratio") >= num(failure, "max_density_ratio"))
        errors.add(&failure, "key '" + key(path, "failure") + "': min_density_ratio must be below max_density_ratio");
    const double dt_max = num(time, "dt_max");
    if (dt_max > 0.0 && dt_max < num(time, "dt_min"))
        errors.add(&time, "key '" + key(path, "time.dt_max") + "': below time.dt_min");
}

std::string sci(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

// A spacing whose particles cannot be held is refused here, naming dp, rather than failing minutes into the
// setup with std::bad_alloc. The coordinator checks against its own machine's memory before it starts
// anything, the participant again against its own: a fluid started on a larger machine (--listen) is still
// refused by a coordinator whose machine could not hold it (the 600 B a particle include the coordinator's
// share, about 185 B, which it holds whatever the fluid's machine).
void check_footprint(const Value& fluid, const std::string& path, Errors& errors) {
    const Footprint f = estimate_footprint(fluid);
    const double memory = physical_memory_bytes();
    const double over_memory = memory > 0 ? f.bytes() / memory : 0.0, over_count = f.particles / kMaxParticles;
    const double over_cells = f.cells / kMaxCells;
    if (over_memory <= 1.0 && over_count <= 1.0 && over_cells <= 1.0) return;
    std::string why;
    if (over_memory > 1.0) why += "; this machine has " + sci(memory / 1e9) + " GB of memory";
    if (over_count > 1.0) why += "; particle ids are 32-bit (at most " + sci(kMaxParticles) + " particles)";
    if (over_cells > 1.0) why += "; grid cell indices are 32-bit (at most " + sci(kMaxCells) + " cells)";
    const double dp = num(fluid, "dp");
    // The water's area dominates what a fine spacing lays out: the count goes as 1/dp^2. Where the tank's
    // walls or its grid cells dominate instead (a tank far larger than its water, often a typo in its size),
    // the tank is the key to name too: "dp" alone sent the reader to the wrong line (a review, 2026-11-28).
    const bool tank_dominates = f.wall_particles > 0.5 * f.particles || over_cells > std::max(over_memory, over_count);
    const Value& tank = fluid.at("tank");
    const std::string tank_too = tank_dominates ? ", or a smaller tank ('" + key(path, "tank") + "' is " +
                                                      schema::number_text(num(tank, "width")) + " m by " +
                                                      schema::number_text(num(tank, "height")) +
                                                      " m; its walls and grid cells are most of this)"
                                                : std::string();
    errors.add(&fluid.at("dp"), "key '" + key(path, "dp") + "': " + sci(dp) + " m lays out about " + sci(f.particles) +
                                    " particles (and " + sci(f.cells) + " grid cells), about " + sci(f.bytes() / 1e9) +
                                    " GB at " + sci(f.bytes_per_particle) + " B a particle" + why +
                                    "; allowed: dp of about " + sci(dp * std::sqrt(std::max({over_memory, over_count, over_cells})) * 1.01) +
                                    " m or more for this geometry" + tank_too);
}

TableSchema build() {
    TableSchema s("The SPH fluid participant (sphfsi-fluid). SI units; 2D, quantities per metre of depth.");
    s.number("dp", "initial particle spacing; sets particle size and mass rho0 * dp^2. A spacing whose particles "
                   "(about 600 B each, coordinator included; PCISPH lists each particle's pairs, about 370 B more at "
                   "h_over_dp = 1.5) exceed this machine's memory is refused")
        .unit("m").greater_than(0).required();
    s.number("h_over_dp", "smoothing length h in units of dp; the support radius is 2h (3h for \"gaussian\"). 1.5: Wendland gradients on the initial lattice are consistent to 0.3 % and 3 wall layers cover the support")
        .at_least(1.0).at_most(4.0).fallback(1.5);
    s.choice("kernel", {"mueller", "poly6", "spiky", "cubic_spline", "wendland", "gaussian"},
             "smoothing kernel: \"mueller\" = the thesis's set (poly6 densities, spiky pressure gradients), "
             "\"wendland\" = Wendland quintic C2, \"cubic_spline\" = cubic B-spline, \"gaussian\" = truncated at 3h")
        .fallback("wendland");
    s.number("rho0", "rest density (bounded as a typo guard: no liquid is above 2.3e4)").unit("kg/m^3").greater_than(0).at_most(1e5).fallback(1000.0);
    s.vector("gravity", 2, "body force per unit mass (also any imposed mean pressure gradient)").unit("m/s^2")
        .at_least(-1e4).at_most(1e4)
        .fallback(Value(Value::Array{Value(0.0), Value(-9.81)}));
    s.choice("periodic", {"none", "x", "y", "xy"},
             "periodic axes; the tank has no walls across a periodic axis. Along one, the water's lattice is spread "
             "evenly over the period, the nearest whole number of particles, while each keeps the mass rho0 dp^2: a "
             "period that is not a whole number of dp starts the water off density by dp / spacing along it, "
             "rarefied below the half (20.3 dp: 1.5 %) and compressed above it (10.7 dp: 2.8 %). Make the period a "
             "whole number of dp")
        .fallback("none");
    s.integer("threads", "OpenMP threads; 0 = all cores the process may use (OMP_NUM_THREADS). Scenes under 4000 "
                         "particles run on one thread: thread synchronisation would cost more than it saves")
        .at_least(0).at_most(1024).fallback(0);
    s.string("step_log", "file to append one line per time step to (step, t, dt, iterations, the largest density "
                         "error of the window so far); "
                         "empty = no per-step log")
        .fallback("");

    TableSchema& tank = s.table("tank", "rectangular tank [0, width] x [0, height] lined with wall particles", true);
    tank.number("width", "inner width").unit("m").greater_than(0).required();
    tank.number("height", "inner height (height of the side walls)").unit("m").greater_than(0).required();
    tank.integer("wall_layers", "layers of wall particles (the kernel support must fit: >= support radius / dp)")
        .at_least(1).at_most(kMaxWallLayers).fallback(3);
    tank.boolean("closed_top", "put a wall (the lid) along the top too").fallback(false);
    tank.vector("lid_velocity", 2, "velocity of the lid, sliding in its plane (Couette flow)").unit("m/s")
        .fallback(Value(Value::Array{Value(0.0), Value(0.0)}));

    TableSchema& water = s.table_array("water", "rectangular blocks of water, filled on a dp lattice");
    water.number("x0", "left edge").unit("m").required();
    water.number("y0", "bottom edge").unit("m").required();
    water.number("width", "width").unit("m").greater_than(0).required();
    water.number("height", "height").unit("m").greater_than(0).required();
    // Negative tags are the walls' and solids' in the record (-1, -2); a split block uses tag + 1 too.
    water.integer("tag", "dye tag recorded for every particle of the block (negative tags mark walls and solids)")
        .at_least(0).at_most(1e9).fallback(0);
    water.choice("split", {"none", "vertical", "horizontal"},
                 "dye the block's two halves differently: tag for the left/bottom half, tag + 1 for the other")
        .fallback("none");

    TableSchema& obstacle = s.table_array("obstacle", "static solid boxes inside the tank, filled with wall particles; water deeper inside "
                                                         "one than its wall layers reach, or whose step crosses its middle, stops the run");
    obstacle.number("x0", "left edge").unit("m").required();
    obstacle.number("y0", "bottom edge").unit("m").required();
    obstacle.number("width", "width").unit("m").greater_than(0).required();
    obstacle.number("height", "height").unit("m").greater_than(0).required();

    TableSchema& gate = s.table("gate", "a vertical gate standing on the floor that holds the water until t = 0 "
                                        "and then rises at a constant speed until its bottom is where its top was "
                                        "(the release of a dam-break experiment); without it the water is released "
                                        "at once. Solid particles, like a coupled structure's; not with an "
                                        "interface mesh. It does not explain the lag of Martin & Moyce's front, "
                                        "and the outflow under it is not validated (docs/validation.md, \"Dam "
                                        "break\")");
    gate.number("x0", "left face").unit("m").required();
    gate.number("thickness", "thickness; 0 = tank.wall_layers dp, a full kernel support").unit("m").at_least(0).fallback(0.0);
    gate.number("height", "height above the floor; 0 = the tank height").unit("m").at_least(0).fallback(0.0);
    gate.number("lift_speed", "speed at which the gate rises from t = 0").unit("m/s").greater_than(0).at_most(1e3).required();

    TableSchema& pressure = s.table("pressure", "pressure model");
    pressure.choice("model", {"standard", "wcsph", "pcisph"},
                    "\"standard\": p = k (rho - rho0) (the thesis's standard SPH); \"wcsph\": Tait equation; "
                    "\"pcisph\": predictive-corrective incompressible SPH (Solenthaler & Pajarola 2009)")
        .fallback("wcsph");
    pressure.number("k", "stiffness of the standard SPH equation of state").unit("m^2/s^2").greater_than(0).fallback(1000.0);
    pressure.number("c0", "WCSPH speed of sound; 0 = 10 u_max (bounded as a typo guard: water's own is 1480)").unit("m/s").at_least(0).at_most(1e5).fallback(0.0);
    pressure.number("u_max", "expected largest flow speed for c0 = 10 u_max; 0 = sqrt(2 |g| H) with H the highest water top")
        .unit("m/s").at_least(0).fallback(0.0);
    // Upper bounds far beyond any water model: 1e300 passed and the first step's acceleration was NaN.
    pressure.number("gamma", "Tait exponent").at_least(1).at_most(20).fallback(7.0);
    pressure.number("background", "background pressure added to the equation of state").unit("Pa")
        .at_least(-1e9).at_most(1e9).fallback(0.0);
    pressure.boolean("clamp_negative",
                     "set negative fluid pressures to zero (stops free-surface particles from pulling together, "
                     "which summation densities would otherwise cause); Adami walls follow it. Off, the walls pull "
                     "where the fluid is under tension and draw it towards their surface (a full closed box under "
                     "gravity pointing up: the bottom row moved 0.4 - 0.6 dp towards the floor in 0.1 s); PCISPH "
                     "off cannot run with a free surface (its deficit counts as expansion)")
        .fallback(true);
    pressure.boolean("kernel_correction",
                     "correct each pair's kernel gradient in the pressure term by the mean of the two particles' "
                     "inverse moment matrices, so that uneven arrangements carry no spurious shear stress (conserves "
                     "momentum; not at the free surface; fluid/include/sphfsi/fluid/pressure_correction.hpp)")
        .fallback(false);
    pressure.number("eta", "PCISPH: iterate until the largest density error is below eta * rho0")
        .greater_than(0).less_than(1).fallback(0.01);
    pressure.integer("min_iterations", "PCISPH: fewest corrections per step").at_least(1).at_most(1000).fallback(3);
    pressure.integer("max_iterations", "PCISPH: most corrections before the step is halved and retried (at least min_iterations)")
        .at_least(3).at_most(10000).fallback(50);

    TableSchema& density = s.table("density", "how densities are obtained");
    density.choice("method", {"summation", "shepard", "continuity"},
                   "\"summation\": rho = sum m_sum W, with m_sum = rho0 / (sum W on the initial lattice) so that water at rest "
                   "on it is at rho0; \"shepard\": summation divided by the Shepard sum sum V_j W with the volumes "
                   "V = m_sum / rho of the plain sums (CSPM; with pcisph the pressure solve predicts and corrects plain "
                   "sums all the same, and shepard reaches only the other terms and the record); \"continuity\": "
                   "integrate drho/dt = sum m (v_i - v_j) . grad W")
        .fallback("continuity");
    density.choice("diffusion", {"none", "molteni", "fourtakas"},
                   "delta-SPH density diffusion in the continuity equation: Molteni & Colagrossi (2009), or "
                   "Fourtakas et al. (2019) which diffuses only the non-hydrostatic part")
        .fallback("none");
    density.number("delta", "density diffusion coefficient").at_least(0).fallback(0.1);
    density.integer("reinitialise_every",
                    "continuity only: every this many steps, replace the integrated densities by the \"shepard\" "
                    "method's sums of the positions then, which depend on the positions alone (Colagrossi & "
                    "Landrini 2003 instead filter the integrated densities every 20 - 30 steps); 0 = never")
        .at_least(0).at_most(1000000).fallback(0);

    TableSchema& viscosity = s.table("viscosity", "viscous term");
    viscosity.choice("model", {"none", "artificial", "morris", "mueller"},
                     "\"artificial\": Monaghan (1992) with alpha; \"morris\": laminar, Morris et al. (1997); "
                     "\"mueller\": Laplacian of Mueller's viscosity kernel (the thesis)")
        .fallback("artificial");
    viscosity.number("alpha", "artificial viscosity coefficient (0.01 - 0.1 is usual)").at_least(0).at_most(10).fallback(0.01);
    viscosity.number("nu", "kinematic viscosity for \"morris\" and \"mueller\"").unit("m^2/s").at_least(0).fallback(1e-6);

    TableSchema& boundary = s.table("boundary", "wall and solid particles");
    boundary.choice("model", {"dummy", "adami"},
                    "\"dummy\": wall particles get density and pressure like fluid particles (the thesis's ghost "
                    "particles); \"adami\": pressure extrapolated from the fluid (Adami, Hu & Adams 2012)")
        .fallback("adami");
    boundary.choice("slip", {"no_slip", "free_slip"},
                    "\"no_slip\": viscous terms see walls and solids moving, with \"adami\" at the ghost velocity "
                    "2 v_wall - v extrapolated from the fluid (Adami), with \"dummy\" at their own velocity (the "
                    "thesis's: the no-slip plane then lies inside the wall, and Morris's Couette flow at L/20 is "
                    "2.8 % off in L2, against 0.04 % with adami); \"free_slip\": no viscous interaction with walls "
                    "or solids, on either side of a pair")
        .fallback("no_slip");
    boundary.boolean("repulsive", "add Monaghan's (1994) repulsive wall force within dp of a wall particle: the "
                                  "non-penetration guard for spray, which carries no pressure for the Adami walls to push "
                                  "back with (turn it on for violent impacts, e.g. scenarios/elastic_obstacle.toml)")
        .fallback(false);
    boundary.number("repulsive_d", "strength D of the repulsive force; 0 = 5 |g| H with H the highest water top")
        .unit("m^2/s^2").at_least(0).at_most(1e6).fallback(0.0);

    TableSchema& surface = s.table("free_surface", "free-surface detection and wind stress");
    surface.number("threshold", "a particle is on the free surface when the divergence of position (2 inside the "
                                "fluid, in 2D) is below this; with wind, within reach of a tank wall it is counted with the wall's particles "
                                "replaced by the mirror image of the water (and of whatever stands in it) across its surface, so "
                                "that a dry wall above the water does not count as water "
                                "(the participant is 2D; the core scales the threshold by Dim/2 for a 3D one)")
        .greater_than(0).less_than(2).fallback(1.5);
    surface.vector("wind_shear", 2, "shear stress applied to the free surface (wind): each free-surface particle "
                                    "carries it on its share of the surface (dp on the initial lattice; measured "
                                    "along the surface as the layer rearranges, the surface mirrored at the tank's "
                                    "walls where it meets them), so the total force is tau times the surface "
                                    "length: exactly on the initial lattice, up to about 2 % less where the surface layer disorders; the "
                                    "record's window column fluid.wind_surface_length is the surface it acted on").unit("Pa")
        .fallback(Value(Value::Array{Value(0.0), Value(0.0)}));

    TableSchema& time = s.table("time", "time stepping");
    time.choice("integrator", {"symplectic_euler", "velocity_verlet", "predictor_corrector"},
                "\"symplectic_euler\": semi-implicit Euler (the thesis); \"velocity_verlet\": kick-drift-kick; "
                "\"predictor_corrector\": Monaghan's midpoint predictor-corrector (two evaluations per step)")
        .fallback("symplectic_euler");
    // The cap lies above the linear stability limits of the leapfrog-type integrators (cfl 1.76 to 2.33 by
    // kernel and h/dp, docs/validation.md) so that stability studies can cross them; 0.4 is the thesis's
    // (as is force_factor = 0.25).
    time.number("cfl", "lambda_v in dt <= lambda_v h / (c + |u|); above about 1.8 the acoustic modes are "
                       "unstable (docs/validation.md)").greater_than(0).at_most(4).fallback(0.4);
    // Capped like cfl, well above the default, so that a study can take this condition out of the way.
    time.number("force_factor", "lambda_F in dt <= lambda_F sqrt(h / |a|)").greater_than(0).at_most(10).fallback(0.25);
    time.number("viscous_factor", "lambda_nu in dt <= lambda_nu h^2 / nu").greater_than(0).at_most(1).fallback(0.125);
    time.number("dt_min", "step floor: a stable step below it stops the run as diverged").unit("s").greater_than(0).at_most(1.0).fallback(1e-8);
    time.number("dt_max", "largest step; 0 = no cap").unit("s").at_least(0).fallback(0.0);

    TableSchema& failure = s.table("failure", "bounds beyond which the run stops as diverged");
    failure.number("min_density_ratio", "smallest rho / rho0 of a fluid particle; also the floor of a wall or solid "
                                        "particle's density (0.01 where this is 0)")
        .at_least(0)
        .fallback(0.01);
    failure.number("max_density_ratio", "largest rho / rho0 of a fluid particle").greater_than(1).fallback(1.5);
    // Why 1 by default: at |v| >= c0 no pressure wave can warn a particle's neighbours ahead of it, so a
    // weakly compressible model is meaningless there whatever the scene; a runaway particle crosses it within
    // a few steps, long before its density or the step floor gives it away. Scenes that know their speeds
    // tighten it (the c0 = 10 u_max rule means a healthy flow stays near 0.1).
    failure.number("max_mach", "largest speed / c0 of a fluid particle (c0: pressure.c0, else 10 u_max; standard "
                               "SPH: sqrt(k)); no bound where c0 is 0").greater_than(0).fallback(1.0);

    // Sub-tables the scene leaves out stand for their defaults (the schema only fills keys that are present).
    s.check([](const Value& fluid, const std::string& path, Errors& errors) {
        const Value full = with_defaults(fluid);
        check_boxes_inside_tank(full, path, errors);
        check_gate(full, path, errors);
        check_combinations(full, path, errors);
        check_footprint(full, path, errors);
    });
    return s;
}

}  // namespace

sphfsi::Value with_defaults(const sphfsi::Value& fluid) {
    Value out = fluid;
    for (const auto& f : scene_schema().fields()) {
        if (f.kind() != sphfsi::schema::Field::Kind::Table || out.find(f.name())) continue;
        // A table with required keys (gate) has no defaults: left out, it is not there.
        const auto& keys = f.table()->fields();
        if (std::any_of(keys.begin(), keys.end(), [](const auto& k) { return k.is_required(); })) continue;
        Errors ignored;  // an empty table of defaults cannot be invalid
        out.as_table_mut()[f.name()] = f.table()->validate(Value(Value::Table{}), f.name(), ignored);
    }
    return out;
}

sphfsi::Value validate_scene(const sphfsi::Value& fluid, const std::string& source) {
    Errors errors;
    Value checked = scene_schema().validate(fluid, "fluid", errors);
    sphfsi::schema::throw_if_any(errors, source);
    return with_defaults(checked);
}

PeriodicAxes periodic_axes(const Value& fluid) {
    const Value* p = fluid.find("periodic");
    const std::string axes = p && p->is_string() ? p->as_string() : "none";
    return {axes == "x" || axes == "xy", axes == "y" || axes == "xy"};
}

GateBox gate_box(const Value& fluid) {
    const Value& gate = fluid.at("gate");
    const Value& tank = fluid.at("tank");
    const double thickness = num(gate, "thickness"), height = num(gate, "height");
    return GateBox{num(gate, "x0"),
                   thickness > 0 ? thickness : static_cast<double>(tank.at("wall_layers").as_int()) * num(fluid, "dp"),
                   height > 0 ? height : num(tank, "height")};
}

const sphfsi::schema::TableSchema& scene_schema() {
    static const TableSchema schema = build();
    return schema;
}

}  // namespace sphfsi::fluid
