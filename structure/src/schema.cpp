#include "sphfsi/structure/schema.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <vector>

namespace sphfsi::structure {
namespace {

// Coordinates beyond 1000 km are typos (1e300 passed the check and then failed the modal analysis with no
// key named: element stiffnesses like EI / L^3 underflow); no structure this tool models comes near.
constexpr double kFar = 1e6;
constexpr long long kMaxElements = 4000;

using schema::Errors;
using schema::TableSchema;

struct Point {
    double x, y;
};

Point point_of(const Value& v) {
    auto d = v.as_doubles();
    return {d[0], d[1]};
}

std::string show(Point p) {
    std::ostringstream s;
    s << "[" << p.x << ", " << p.y << "]";
    return s.str();
}

// The keys that make a load time-dependent; shared by point and distributed loads.
void add_history_keys(TableSchema& t) {
    t.choice("history", {"constant", "ramp", "sine"},
             "time factor f(t) applied to the load while start_time <= t < end_time: constant 1; "
             "ramp min((t-start_time)/ramp_time, 1); sine sin(2 pi frequency (t-start_time) + phase)")
        .fallback("constant");
    t.number("ramp_time", "duration of the linear ramp from 0 to the full load (history = \"ramp\")")
        .unit("s").greater_than(0).fallback(1.0);
    // At most 1 MHz: the structure steps 20 times a period (time.steps_per_period), and beyond that the step
    // would vanish (1e307 Hz made it 0, a review, 2026-11-27).
    t.number("frequency", "frequency of the sine (history = \"sine\")").unit("Hz").greater_than(0).at_most(1e6).fallback(1.0);
    t.number("phase", "phase of the sine at start_time (history = \"sine\")").unit("rad").fallback(0.0);
    t.number("start_time", "the load is zero before this time").unit("s").fallback(0.0);
    t.number("end_time", "the load is zero from this time on; absent = never switched off. Steps the structure "
                         "chooses (alone, between outputs) end on start_time and end_time, so a pulse shorter "
                         "than a step is applied whole; a sub-step the coupling counts that a switch falls inside takes the "
                         "load's mean over that sub-step, which carries the load's impulse spread over the sub-step")
        .unit("s");
}

void add_point_load_keys(TableSchema& t) {
    t.vector("at", 2, "where the load acts; must coincide with a node of some member").unit("m").at_least(-kFar).at_most(kFar)
        .required();
    t.vector("force", 2, "force [Fx, Fy] in global axes, on the whole depth b").unit("N").fallback(Value::Array{0.0, 0.0});
    t.number("moment", "in-plane moment, counter-clockwise positive, on the whole depth b").unit("N m").fallback(0.0);
}

// Node positions exactly as the model builder creates them: start + k/n (end - start).
struct MemberGeometry {
    Point a, b;
    std::int64_t n;
    Point node(std::int64_t k) const {
        double s = static_cast<double>(k) / static_cast<double>(n);
        return {a.x + s * (b.x - a.x), a.y + s * (b.y - a.y)};
    }
    double length() const { return std::hypot(b.x - a.x, b.y - a.y); }
};

std::vector<MemberGeometry> members_of(const Value& table) {
    std::vector<MemberGeometry> out;
    if (const Value* ms = table.find("members"))
        for (const Value& m : ms->as_array())
            out.push_back({point_of(m.at("start")), point_of(m.at("end")), m.at("n_elements").as_int()});
    return out;
}

// Points closer than this are the same node. Relative to the largest member so that scenes in
// millimetres and in kilometres behave alike; far above round-off of the node interpolation.
double node_tolerance(const std::vector<MemberGeometry>& members) {
    double size = 0.0;
    for (const auto& m : members) size = std::max(size, m.length());
    return 1e-6 * size;
}

bool on_a_node(const std::vector<MemberGeometry>& members, Point p, double tol) {
    for (const auto& m : members)
        for (std::int64_t k = 0; k <= m.n; ++k) {
            Point q = m.node(k);
            if (std::hypot(q.x - p.x, q.y - p.y) <= tol) return true;
        }
    return false;
}

// Two members with a node at p where no member ends: they cross there without a joint (the model builder
// joins members only at their ends), and a support or load at p would act on one of them, the first listed,
// while the other moves freely (a review, 2026-11-28).
std::optional<std::pair<std::size_t, std::size_t>> unjoined_crossing(const std::vector<MemberGeometry>& members, Point p,
                                                                     double tol) {
    auto near = [&](Point q) { return std::hypot(q.x - p.x, q.y - p.y) <= tol; };
    std::vector<std::size_t> with_node;
    for (std::size_t i = 0; i < members.size(); ++i) {
        if (near(members[i].a) || near(members[i].b)) return std::nullopt;  // a joint: one node for all
        for (std::int64_t k = 1; k < members[i].n; ++k)
            if (near(members[i].node(k))) {
                with_node.push_back(i);
                break;
            }
    }
    if (with_node.size() < 2) return std::nullopt;
    return std::pair{with_node[0], with_node[1]};
}

// Every table_array entry whose `at` must be a node.
void check_points_on_nodes(const Value* entries, const std::string& path, const std::vector<MemberGeometry>& members,
                           double tol, Errors& errors) {
    if (!entries) return;
    std::size_t i = 0;
    for (const Value& e : entries->as_array()) {
        Point p = point_of(e.at("at"));
        if (!on_a_node(members, p, tol))
            errors.add(&e, "key '" + path + "[" + std::to_string(i) + "].at': " + show(p) +
                               " is not a node of any member; nodes are start + k/n_elements (end - start)");
        else if (const auto crossing = unjoined_crossing(members, p, tol))
            errors.add(&e, "key '" + path + "[" + std::to_string(i) + "].at': " + show(p) + " is where members[" +
                               std::to_string(crossing->first) + "] and members[" + std::to_string(crossing->second) +
                               "] cross without a joint (members join only where one ends); it would hold only "
                               "one of them: end a member there to join them, or move it");
        ++i;
    }
}

void check_structure(const Value& s, const std::string& path, Errors& errors) {
    const auto members = members_of(s);
    // Member errors point at the member's own table (its line in the scene), not at [structure].
    auto member_value = [&](std::size_t i) { return &s.at("members").as_array()[i]; };
    if (members.empty()) {
        errors.add(&s, "key '" + path + ".members': at least one [[" + path + ".members]] is needed");
        return;
    }
    const double tol = node_tolerance(members);

    // Double precision bounds the mesh: a slender chain of N elements has K's condition number about 34 N^4
    // (highest over lowest bending omega^2), 1e16 near N = 4000. Measured on beam_only.toml (2026-11-26):
    // mode 1 to 4e-7 up to 4000 elements, then off by 0.1 - 0.8 % at 5000 - 20000 (the modal analysis feeds
    // Rayleigh damping, the accuracy step limit and initial.mode). No coupled scene needs elements finer
    // than the fluid's spacing, far below this.
    long long elements = 0;
    for (const auto& m : members) elements += m.n;
    if (elements > kMaxElements)
        errors.add(&s, "key '" + path + ".members': " + std::to_string(elements) + " elements in all; allowed: at most " +
                           std::to_string(kMaxElements) + " (beyond, double precision cannot resolve the lowest modes)");

    // An element no longer than the node tolerance has both ends at one node: the model builder then refused it
    // from the participant, naming no scene line and "elements of length 0.000000 m" (a review, 2026-11-28).
    for (std::size_t i = 0; i < members.size(); ++i)
        if (const double element = members[i].length() / static_cast<double>(members[i].n); !(element > tol))
            errors.add(member_value(i), "key '" + path + ".members[" + std::to_string(i) + "]': " +
                                            std::to_string(members[i].n) + " elements of " + schema::number_text(element) +
                                            " m; allowed: elements longer than " + schema::number_text(tol) +
                                            " m (1e-6 of the longest member, within which points are one node)");

    // Members connect only at nodes; an end that lands between two nodes of another member would be
    // silently disconnected, which is never what the engineer meant.
    for (std::size_t i = 0; i < members.size(); ++i) {
        for (Point end : {members[i].a, members[i].b}) {
            for (std::size_t j = 0; j < members.size(); ++j) {
                if (i == j) continue;
                const auto& m = members[j];
                double L = m.length();
                double ex = (m.b.x - m.a.x) / L, ey = (m.b.y - m.a.y) / L;
                double s_along = (end.x - m.a.x) * ex + (end.y - m.a.y) * ey;
                double off = std::abs(-(end.x - m.a.x) * ey + (end.y - m.a.y) * ex);
                if (off > tol || s_along < -tol || s_along > L + tol) continue;
                bool at_node = false;
                for (std::int64_t k = 0; k <= m.n && !at_node; ++k) {
                    Point q = m.node(k);
                    at_node = std::hypot(q.x - end.x, q.y - end.y) <= tol;
                }
                if (!at_node)
                    errors.add(member_value(i), "key '" + path + ".members[" + std::to_string(i) + "]': end " + show(end) +
                                       " lies on members[" + std::to_string(j) +
                                       "] between two of its nodes; members connect only at nodes, so choose "
                                       "n_elements of members[" + std::to_string(j) + "] to put a node there");
            }
        }
    }

    // Collinear members over a shared stretch are not joined there (only ends meet nodes): each would carry
    // its own stiffness and mass, a silently doubled structure.
    for (std::size_t i = 0; i < members.size(); ++i)
        for (std::size_t j = 0; j < i; ++j) {
            const auto& m = members[j];
            const double L = m.length(), ex = (m.b.x - m.a.x) / L, ey = (m.b.y - m.a.y) / L;
            auto along = [&](Point p) { return (p.x - m.a.x) * ex + (p.y - m.a.y) * ey; };
            auto off = [&](Point p) { return std::abs(-(p.x - m.a.x) * ey + (p.y - m.a.y) * ex); };
            if (off(members[i].a) > tol || off(members[i].b) > tol) continue;
            const double lo = std::min(along(members[i].a), along(members[i].b)),
                         hi = std::max(along(members[i].a), along(members[i].b));
            if (std::min(hi, L) - std::max(lo, 0.0) > tol)
                errors.add(member_value(i), "key '" + path + ".members[" + std::to_string(i) + "]': lies along members[" +
                                   std::to_string(j) + "] over a common stretch; members may meet at nodes but not overlap");
        }

    check_points_on_nodes(s.find("supports"), path + ".supports", members, tol, errors);
    check_points_on_nodes(s.find("point_loads"), path + ".point_loads", members, tol, errors);
    if (const Value* init = s.find("initial"))
        check_points_on_nodes(init->find("preload"), path + ".initial.preload", members, tol, errors);

    if (const Value* sup = s.find("supports")) {
        const auto& a = sup->as_array();
        for (std::size_t i = 0; i < a.size(); ++i)
            for (std::size_t j = 0; j < i; ++j) {
                Point p = point_of(a[i].at("at")), q = point_of(a[j].at("at"));
                if (std::hypot(p.x - q.x, p.y - q.y) <= tol)
                    errors.add(&a[i], "key '" + path + ".supports[" + std::to_string(i) + "]': same node as supports[" +
                                          std::to_string(j) + "]; give one support per node");
            }
    }

    if (const Value* dl = s.find("distributed_loads")) {
        std::size_t i = 0;
        for (const Value& d : dl->as_array()) {
            auto m = d.at("member").as_int();
            if (m >= static_cast<std::int64_t>(members.size()))
                errors.add(&d, "key '" + path + ".distributed_loads[" + std::to_string(i) + "].member': " +
                                   std::to_string(m) + " but there are only " + std::to_string(members.size()) +
                                   " members (indices from 0)");
            ++i;
        }
    }

    if (const Value* init = s.find("initial")) {
        // preload = [] loads nothing: no static start (the solver reads it so too, FrameDynamics::reset).
        const Value* preload = init->find("preload");
        bool statics = init->at("static_equilibrium").as_bool() || (preload && preload->is_array() && !preload->as_array().empty());
        const auto mode = init->at("mode").as_int();
        if (statics && mode > 0)
            errors.add(init, "key '" + path + ".initial': a mode-shape start (mode > 0) and a static start "
                             "(static_equilibrium / preload) exclude each other; choose one");
        // Three DOF a node bound the modes; joints and supports take some, which INIT then reports exactly.
        long long nodes = 0;
        for (const auto& m : members) nodes += m.n + 1;
        if (mode > 3 * nodes)
            errors.add(&init->at("mode"), "key '" + path + ".initial.mode': " + std::to_string(mode) + " but the structure has " +
                                              std::to_string(nodes) + " nodes at most, so at most " +
                                              std::to_string(3 * nodes) + " modes; allowed: at most " + std::to_string(3 * nodes));
        // Either half of a mode start alone does nothing, which is never what was meant.
        const bool amplitude = init->at("mode_amplitude").as_double() != 0.0;
        if (mode > 0 && !amplitude)
            errors.add(init, "key '" + path + ".initial.mode_amplitude': a mode start (mode = " + std::to_string(mode) +
                                 ") needs a non-zero mode_amplitude");
        if (mode == 0 && amplitude)
            errors.add(&init->at("mode_amplitude"), "key '" + path + ".initial.mode_amplitude': set without initial.mode; "
                                                    "allowed with mode = 0: 0");
    }
}

void check_history(const Value& t, const std::string& path, Errors& errors) {
    if (const Value* end = t.find("end_time"))
        if (!(end->as_double() > t.at("start_time").as_double()))
            errors.add(end, "key '" + path + ".end_time': must be after start_time");
}

TableSchema build() {
    TableSchema s(
        "Plane frame of Euler-Bernoulli beams (axial + bending, 3 DOF per node) in SI units. The model is a "
        "slab of depth b (section.depth): stiffness and mass are those of the b-deep section, scene loads are "
        "totals on that depth, and the fluid's forces (2D, N per metre of depth) are multiplied by b.");

    s.choice("formulation", {"linear", "corotational"},
             "\"linear\": small displacements, one linear solve per step with a reused factorization; "
             "\"corotational\": large rotations (Crisfield/Battini), Newton iterations per step")
        .fallback("linear");
    s.choice("mass", {"consistent", "lumped"},
             "mass matrix: consistent (Hermitian cubic) or lumped (rho A L/2 per node, rotary rho A L^3/78, HRZ); "
             "corotational runs keep each element's consistent matrix in its reference orientation (lumped is the "
             "same in every orientation)")
        .fallback("consistent");
    s.boolean("gravity", "apply self-weight rho A g as a distributed load on every member").fallback(false);
    s.vector("gravity_vector", 2, "gravitational acceleration used when gravity = true").unit("m/s^2")
        .fallback(Value::Array{0.0, -9.81});

    auto& mat = s.table("material", "Linear elastic isotropic material.", true);
    // Material and section bounds far beyond any real structure (the stiffest solids are near 1e12 Pa, the
    // densest near 2.3e4 kg/m^3; the added-mass sweep goes down to 0.3): 1e308 Pa or 1e-300 kg/m^3 passed and
    // broke the modal analysis, with no key named.
    mat.number("E", "Young's modulus").unit("Pa").at_least(1.0).at_most(1e13).required();
    mat.number("nu", "Poisson's ratio; used only when section.plane_strain = true").at_least(0).less_than(0.5)
        .fallback(0.3);
    mat.number("rho", "density").unit("kg/m^3").at_least(1e-3).at_most(1e6).required();

    auto& sec = s.table("section", "Solid rectangular cross-section: A = b t, I = b t^3 / 12.", true);
    sec.number("thickness", "in-plane thickness t (also the distance between the two wetted faces)").unit("m")
        .greater_than(0).at_most(1e3).required();
    sec.number("depth", "out-of-plane depth b; the fluid is 2D per metre of depth, keep 1 unless you mean it")
        .unit("m").greater_than(0).at_most(1e3).fallback(1.0);
    sec.boolean("plane_strain",
                "use E / (1 - nu^2): a plate strip in cylindrical bending (a gate spanning the whole channel)")
        .fallback(false);

    auto& mem = s.table_array("members", "Straight members from start to end, meshed with n_elements equal "
                                         "elements. A member end that meets a node of another member is rigidly joined to it.");
    mem.string("name", "a label for the reader of the scene (messages name members by their index, members[i])");
    mem.vector("start", 2, "first end point").unit("m").at_least(-kFar).at_most(kFar).required();
    mem.vector("end", 2, "second end point").unit("m").at_least(-kFar).at_most(kFar).required();
    mem.integer("n_elements", "number of equal beam elements (4000 at most over all members)").at_least(1).at_most(4000)
        .fallback(10);
    mem.boolean("wetted", "publish this member's faces (at +-t/2) as fluid interface").fallback(true);
    mem.vector("interface_padding", 2,
               "[left, right]: extend the published cross-section beyond the faces on the member's left side "
               "(counter-clockwise from start to end) and right side. The fluid fills the cross-section with solid "
               "particles at about its own spacing, and a plate thinner than the kernel support lets water through: pad "
               "a side that stays dry (the mesh moves rigidly with the section, so mapping stays exact)")
        .unit("m").at_least(0).fallback(Value::Array{0.0, 0.0});
    mem.check([](const Value& m, const std::string& path, Errors& errors) {
        Point a = point_of(m.at("start")), b = point_of(m.at("end"));
        if (!(std::hypot(b.x - a.x, b.y - a.y) > 0.0))
            errors.add(&m, "key '" + path + "': start and end are the same point; a member needs length > 0");
    });

    auto& sup = s.table_array("supports", "Supports at nodes; nodes without one are free.");
    sup.vector("at", 2, "the supported node").unit("m").at_least(-kFar).at_most(kFar).required();
    sup.choice("type", {"clamped", "pinned", "roller", "free"},
               "clamped: ux, uy, theta fixed; pinned: ux, uy fixed; roller: motion along `normal` fixed; free: none")
        .required();
    sup.vector("normal", 2, "roller only: the restrained direction (normal of the rolling surface)")
        .fallback(Value::Array{0.0, 1.0});
    sup.check([](const Value& t, const std::string& path, Errors& errors) {
        Point n = point_of(t.at("normal"));
        if (!(std::hypot(n.x, n.y) > 0.0)) errors.add(&t, "key '" + path + ".normal': must not be [0, 0]");
    });

    auto& pl = s.table_array("point_loads", "Dead (non-follower) point loads at nodes.");
    add_point_load_keys(pl);
    add_history_keys(pl);
    pl.check(check_history);

    auto& dl = s.table_array("distributed_loads",
                             "Dead uniform loads per unit reference length of a member, in global axes.");
    dl.integer("member", "index of the loaded member in [[members]], from 0").at_least(0).required();
    dl.vector("q", 2, "load intensity [qx, qy] on the whole depth b").unit("N/m").required();
    add_history_keys(dl);
    dl.check(check_history);

    auto& damp = s.table("damping", "Viscous damping matrix D in M a + D v + f_int(u) = f_ext.");
    damp.choice("model", {"none", "simple", "rayleigh"},
                "none: D = 0; simple: D = c M (the thesis's matrix, damping ratio c / (2 omega) in every mode); "
                "rayleigh: D = alpha M + beta K0 from target ratios at two frequencies (corotational: beta damps each "
                "element's local deformation, so rigid rotations are not damped; its rate is the deformation's change "
                "over the step, a mid-step rate, so newmark, which balances forces at the step's end, is first order "
                "in that term; generalized_alpha at rho_inf = 0.9 balances 0.026 dt from the middle)")
        .fallback("none");
    damp.number("c", "coefficient of the simple model D = c M").unit("1/s").at_least(0).fallback(0.0);
    damp.vector("ratios", 2, "rayleigh: target damping ratios zeta1, zeta2 at the two frequencies").at_least(0)
        .less_than(1).fallback(Value::Array{0.02, 0.02});
    damp.vector("frequencies", 2,
                "rayleigh: the two frequencies f1 < f2; absent = the 1st and the time.resolved_modes-th "
                "natural frequency (the 2nd when resolved_modes = 1; the next one computed if that equals the 1st)")
        .unit("Hz").greater_than(0);
    damp.check([](const Value& t, const std::string& path, Errors& errors) {
        if (const Value* f = t.find("frequencies")) {
            auto v = f->as_doubles();
            if (!(v[0] < v[1])) errors.add(f, "key '" + path + ".frequencies': need f1 < f2");
        }
    });

    auto& time = s.table("time", "Time integration.");
    time.choice("integrator", {"backward_euler", "newmark", "generalized_alpha"},
                "backward_euler: first order, strongly damped (the thesis's choice); newmark: average "
                "acceleration, second order, energy conserving when linear but can go unstable for large "
                "corotational motions at coarse steps; generalized_alpha: second order with high-frequency "
                "damping set by rho_inf (Chung & Hulbert 1993), the default; in large corotational motions it "
                "too can create energy at coarse steps, later than newmark (failure.max_energy_created stops "
                "such a run)")
        .fallback("generalized_alpha");
    time.number("rho_inf", "generalized_alpha: spectral radius at omega dt -> infinity (1 = no damping)")
        .at_least(0).at_most(1).fallback(0.9);
    time.number("dt_max", "largest step the structure asks for (ADVANCED dt_wanted); sub-steps the coordinator "
                          "sets are taken as sent").unit("s").at_least(1e-12).fallback(1e-3);
    time.integer("resolved_modes", "the accuracy limit on the step resolves this many lowest elastic modes")
        .at_least(1).at_most(50).fallback(3);
    time.number("steps_per_period", "accuracy limit: at least this many steps per period of the highest resolved mode, "
                                    "and of every sine point or distributed load")
        .at_least(2).at_most(1e6).fallback(20.0);
    time.number("max_numerical_damping",
                "backward_euler only: largest algorithmic damping ratio ln(1+W^2)/(2 atan W), W = omega dt, "
                "tolerated in the highest resolved mode")
        .greater_than(0).at_most(0.5).fallback(0.05);

    auto& newton = s.table("newton", "Newton-Raphson iterations (corotational steps, static solves).");
    newton.number("tolerance", "converged when |residual| <= tolerance * largest force term (free DOFs), or "
                               "when it stops halving below sqrt(tolerance) * that (round-off floor of big models; it also "
                               "accepts an iteration converging slowly there, as with an approximate tangent)")
        .greater_than(0).less_than(1).fallback(1e-8);
    newton.integer("max_iterations", "iterations per step before the run stops with not_converged")
        .at_least(1).at_most(1000).fallback(25);
    newton.integer("load_steps", "static solves (initial equilibrium): load increments").at_least(1).at_most(10000)
        .fallback(10);

    auto& failure = s.table("failure", "When a run stops as diverged (beyond non-finite or absurd displacements).");
    failure.number("max_energy_created",
                   "stop when kinetic + strain energy exceeds the initial energy plus the loads' work by this "
                   "fraction of the largest of (initial energy + |load work|) and (kinetic + strain) so far: "
                   "Newmark and generalized-alpha can create energy in large corotational motions at coarse "
                   "steps; 0 = off")
        .at_least(0).at_most(1).fallback(0.1);

    auto& init = s.table("initial", "Initial state at t0 (default: undeformed, at rest); READY passes the interface's "
                                    "state at t0 on to the fluid and the watchpoints");
    init.boolean("static_equilibrium", "start from static equilibrium under the structure's own loads at t0 (point "
                                       "and distributed loads, self-weight, and any preload); not under the coordinator's [load], "
                                       "which the structure first receives with the first window (a constant [load] "
                                       "with this key is refused)")
        .fallback(false);
    // The modes come from subspace iteration, whose cost grows with their number: mode = 300 of a 400-element
    // beam passed check and then kept INIT past every timeout (a review, 2026-11-27). 50 is resolved_modes' bound.
    init.integer("mode", "start deflected in this natural mode (1 = fundamental), at rest; 0 = off").at_least(0)
        .at_most(50).fallback(0);
    init.number("mode_amplitude", "largest nodal translation of that mode shape; the shape is signed so that its "
                                  "largest translation component (x or y) is positive, so a negative amplitude "
                                  "starts the other way")
        .unit("m")
        .fallback(0.0);
    auto& pre = init.table_array("preload", "Point loads held at t0 and released: a plucked start from rest.");
    add_point_load_keys(pre);

    s.check(check_structure);
    return s;
}

}  // namespace

const schema::TableSchema& scene_schema() {
    static const TableSchema schema = build();
    return schema;
}

Value validated_config(const Value& section, const std::string& source) {
    Value input = section;
    if (input.is_table()) {
        // Present-but-empty optional tables make the validator fill their defaults.
        auto& t = input.as_table_mut();
        for (const char* name : {"damping", "time", "newton", "failure", "initial"})
            if (!t.contains(name)) t[name].make_table();
    }
    schema::Errors errors;
    Value out = scene_schema().validate(input, source, errors);
    schema::throw_if_any(errors, source);
    return out;
}

}  // namespace sphfsi::structure
