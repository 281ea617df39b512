// The structure through the protocol::Solver interface, as the participant runtime drives it.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "scenes.hpp"
#include "sphfsi/structure/participant.hpp"

using namespace structure_test;
using namespace sphfsi::structure;
using namespace sphfsi::protocol;

namespace {
InitRequest request(const Value& scene, std::vector<std::uint8_t> state = {}, double t0 = 0.0) {
    InitRequest r;
    r.config = scene;
    r.t0 = t0;
    r.state = std::move(state);
    return r;
}
// Vertex forces pushing the wetted faces sideways, varying along the member.
Fields forces(const StructureSolver& s, double scale) {
    const auto n = s.interface_map().vertex_count();
    F64Array f = F64Array::zeros(n, 2);
    for (std::size_t i = 0; i < n; ++i) {
        f(i, 0) = scale * 3.0;
        f(i, 1) = -scale * (10.0 + static_cast<double>(i));
    }
    return Fields{{"force", f}};
}
AdvanceRequest window(double t, double dt, std::uint32_t substeps, Fields inputs = {}) {
    AdvanceRequest r;
    r.t = t;
    r.dt = dt;
    r.substeps = substeps;
    r.inputs = std::move(inputs);
    return r;
}
const F64Array& array(const Fields& f, const char* name) { return std::get<F64Array>(f.at(name)); }
std::string code_of(const std::function<void()>& fn) {
    try {
        fn();
    } catch (const SolverError& e) {
        return e.code();
    }
    return "none";
}
Value coupled_scene(const char* formulation = "linear") {
    Value s = beam(10, "clamped", "", formulation);
    set(s, "time.dt_max", Value(1e-3));
    return s;
}
}  // namespace

TEST_SUITE("participant") {
TEST_CASE("init publishes the interface and the step it wants") {
    StructureSolver s;
    const InitReply r = s.init(request(coupled_scene()));
    REQUIRE(r.interface);
    CHECK(r.interface->vertices.shape == std::vector<std::uint64_t>{22, 2});
    CHECK(r.interface->cells.shape == std::vector<std::uint64_t>{10, 4});
    CHECK(r.dt_wanted == doctest::Approx(std::min(1e-3, s.dynamics().dt_accuracy())).scale(0).epsilon(1e-12));
    CHECK(r.info.at("elements").as_int() == 10);
    CHECK(r.info.at("natural_frequencies_hz").at("mode_1").as_double() == doctest::Approx(8.355).epsilon(1e-3));
    CHECK(s.kind() == "structure");
}

// Point loads at the tip of the clamped cantilever (10 linear elements), each on from `start` to `end`.
struct Pulse {
    double start, end, force;
};
// The tip's peak over 250 windows of 1 ms (as the coordinator's to its outputs), each in `substeps`
// sub-steps (0: the participant's choice), with the given integrator.
double peak_after_pulses(const std::vector<Pulse>& pulses, std::uint32_t substeps,
                         const char* integrator = "generalized_alpha") {
    Value scene = beam(10, "clamped", "", "linear");
    set(scene, "time.integrator", Value(integrator));
    Value::Array loads;
    for (const Pulse& pulse : pulses) {
        Value load = point_load(L, 0.0, 0.0, -pulse.force);
        load.as_table_mut()["start_time"] = Value(pulse.start);
        load.as_table_mut()["end_time"] = Value(pulse.end);
        loads.push_back(load);
    }
    set(scene, "point_loads", Value(std::move(loads)));
    StructureSolver s;
    s.init(request(scene));
    const auto tip = 3 * static_cast<Eigen::Index>(s.dynamics().model().node_at({L, 0.0})) + 1;
    Progress p;
    double peak = 0.0;
    for (int k = 0; k < 250; ++k) {
        s.advance(window(k * 1e-3, 1e-3, substeps), p);
        peak = std::max(peak, std::abs(s.dynamics().state().u[tip]));
    }
    return peak;
}

TEST_CASE("a load pulse shorter than a step is applied whole when the steps are the participant's to choose") {
    // Sampled at step ends only, a pulse between two ends was lost: 50 us of 10 kN on a cantilever never
    // moved it (a review, 2026-11-28). The adaptive sub-steps now land on the pulse's ends, where each step
    // takes the load as it is inside the step, so the impulse is applied whole. Reference: the same impulse,
    // 0.5 N s, over 0.2 ms from where a window starts (a step that ended a hair past that start took the load
    // early: twice the impulse). Both pulses are far shorter than the first period (120 ms), so the free
    // vibration after them is the same: a rectangular pulse of length tau scales mode k's amplitude by
    // sin(w_k tau / 2) / (w_k tau / 2), at 0.2 ms 0.99999 for the first mode and above 0.985 for the first
    // five (to 470 Hz); tolerance 1 % on the tip's peak (measured 0.3 %).
    const double short_pulse = peak_after_pulses({{0.10005, 0.1001, 1e4}}, 0);
    const double long_pulse = peak_after_pulses({{0.1, 0.1002, 2500.0}}, 0);
    MESSAGE("tip peak after 0.5 N s: " << short_pulse << " m (50 us), " << long_pulse << " m (0.2 ms)");
    CHECK(long_pulse > 1e-4);
    CHECK(rel(short_pulse, long_pulse) < 0.01);
}

TEST_CASE("a load pulse inside a sub-step counted by the coupling carries its impulse, with every integrator") {
    // Counted sub-steps (here 0.5 ms: 2 a window) cannot land on a pulse's ends. A step that a switch falls
    // inside takes the loads' mean over the step, starting from that mean's acceleration and re-balanced
    // under the load at its end. Before 2026-11-29 it sampled the load at its ends only: a 50 us pulse
    // inside a sub-step never moved the beam (peak 0), and one across two sub-steps was taken as a ramp
    // over both (ten times the impulse); with the mean but no brackets, Newmark took six times a pulse that
    // began where a sub-step did (a review). Reference: the same mean over each sub-step as a load that
    // lands on the sub-steps' ends (1 kN over the whole sub-step for 0.5 N s), so the same sub-steps with
    // the same loads in them: equal to round-off (1e-9). 0.10005 + 5e-5 is not 0.1001 in floating point,
    // hence the explicit ends.
    const double impulse = 0.5, sub_step = 5e-4;
    for (const char* integrator : {"backward_euler", "newmark", "generalized_alpha"}) {
        const double whole = peak_after_pulses({{0.1, 0.1005, impulse / sub_step}}, 2, integrator);
        CHECK(whole > 1e-4);
        for (const auto& [from, to] : {std::pair{0.10005, 0.1001}, {0.1, 0.10005}, {0.1002, 0.10025}, {0.10045, 0.1005}}) {
            const double counted = peak_after_pulses({{from, to, impulse / (to - from)}}, 2, integrator);
            MESSAGE(std::string(integrator) << ": tip peak after 0.5 N s over " << from << " - " << to << " s: " << counted
                               << " m, the sub-step's mean " << whole << " m");
            CHECK(rel(counted, whole) < 1e-9);
        }
        // Across two sub-steps: 20 us of 50 in the first, 30 in the second.
        const double across = peak_after_pulses({{0.10048, 0.10053, impulse / 5e-5}}, 2, integrator);
        const double means = peak_after_pulses({{0.1, 0.1005, 0.4 * impulse / sub_step}, {0.1005, 0.101, 0.6 * impulse / sub_step}},
                                               2, integrator);
        MESSAGE(std::string(integrator) << ": across two sub-steps " << across << " m, their means " << means << " m");
        CHECK(rel(across, means) < 1e-9);
    }
    // And against the physics, generalized-alpha: the 0.2 ms pulse on the participant's own steps (above).
    // Spread over a 0.5 ms step, mode k is scaled by sin(w_k tau / 2) / (w_k tau / 2), 1 - 3e-5 for the
    // first mode, whose vibration the tip's peak mostly is; the rest is the higher modes, which 0.5 ms steps
    // damp differently from the participant's own (generalized-alpha's damping depends on w h). Measured
    // 0.7 % (1.6 % across two sub-steps); tolerance 2 %.
    const double reference = peak_after_pulses({{0.1, 0.1002, 2500.0}}, 0);
    CHECK(rel(peak_after_pulses({{0.10005, 0.1001, 1e4}}, 2), reference) < 0.02);
    CHECK(rel(peak_after_pulses({{0.10048, 0.10053, 1e4}}, 2), reference) < 0.02);
}

TEST_CASE("advance: sub-steps, progress ticks, outputs on the vertices, iterations") {
    StructureSolver s;
    s.init(request(coupled_scene()));
    Progress p;
    const AdvanceReply r = s.advance(window(0.0, 2e-3, 4, forces(s, 1.0)), p);
    CHECK(r.t == 2e-3);
    CHECK(r.substeps == 4);
    CHECK(p.steps.load() == 4);
    CHECK(r.solver_iterations == 4);
    CHECK(array(r.outputs, "displacement").shape == std::vector<std::uint64_t>{22, 2});
    CHECK(array(r.outputs, "velocity").shape == std::vector<std::uint64_t>{22, 2});
    CHECK(array(r.outputs, "displacement")(21, 1) < 0.0);  // pushed down, tip moved down

    // substeps = 0: the solver chooses ceil(dt / dt_wanted).
    const double dt = 3.5 * s.dt_wanted();
    const AdvanceReply r2 = s.advance(window(r.t, dt, 0), p);
    CHECK(r2.substeps == 4);
    CHECK(r2.t == doctest::Approx(r.t + dt).epsilon(1e-15));
}

TEST_CASE("vertex forces act like the same nodal loads applied directly") {
    // A uniform downward vertex force f on every one of the 22 vertices equals 2 f per node, with every
    // integrator: the interface force enters the start's acceleration as the scene's loads do. Before
    // 2026-11-28 it did not, and only backward Euler (which does not use that acceleration) agreed.
    for (const char* integrator : {"backward_euler", "newmark", "generalized_alpha"}) {
        CAPTURE(integrator);
        StructureSolver s;
        Value scene = coupled_scene();
        set(scene, "time.integrator", Value(integrator));
        s.init(request(scene));
        F64Array f = F64Array::zeros(22, 2);
        for (std::size_t i = 0; i < 22; ++i) f(i, 1) = -5.0;
        Progress p;
        s.advance(window(0.0, 1e-3, 2, Fields{{"force", f}}), p);
        s.advance(window(1e-3, 1e-3, 2, Fields{{"force", f}}), p);

        Value::Array loads;
        for (int k = 0; k <= 10; ++k) loads.push_back(point_load(k * L / 10, 0, 0, -10.0));
        set(scene, "point_loads", Value(loads));
        StructureSolver direct;
        direct.init(request(scene));
        direct.advance(window(0.0, 1e-3, 2), p);
        direct.advance(window(1e-3, 1e-3, 2), p);
        const auto& u = direct.dynamics().state().u;
        CHECK((s.dynamics().state().u - u).norm() <= 1e-12 * u.norm());
        CHECK((s.dynamics().state().v - direct.dynamics().state().v).norm() <= 1e-12 * direct.dynamics().state().v.norm());
    }
}

TEST_CASE("linear formulation factorizes once while dt stays the same") {
    StructureSolver s;
    s.init(request(coupled_scene()));
    Progress p;
    double t = 0;
    for (int k = 0; k < 10; ++k) t = s.advance(window(t, 1e-3, 2, forces(s, 1.0)), p).t;
    CHECK(s.dynamics().factorizations() == 1);
    t = s.advance(window(t, 1e-3, 3), p).t;  // new sub-step size
    CHECK(s.dynamics().factorizations() == 2);
    s.advance(window(t, 1.5e-3, 3), p);  // back to 0.5 ms sub-steps: a new factorization, 1 entry cache
    CHECK(s.dynamics().factorizations() == 3);
}

TEST_CASE("save / restore: repeating a window gives identical numbers (implicit coupling)") {
    for (const char* formulation : {"linear", "corotational"}) {
        StructureSolver s;
        s.init(request(coupled_scene(formulation)));
        Progress p;
        s.advance(window(0.0, 2e-3, 2, forces(s, 50.0)), p);
        s.save();
        const AdvanceReply first = s.advance(window(2e-3, 2e-3, 2, forces(s, 80.0)), p);
        s.restore();
        s.advance(window(2e-3, 2e-3, 2, forces(s, 10.0)), p);  // another coupling iterate
        s.restore();
        const AdvanceReply again = s.advance(window(2e-3, 2e-3, 2, forces(s, 80.0)), p);
        CHECK(array(first.outputs, "displacement") == array(again.outputs, "displacement"));
        CHECK(array(first.outputs, "velocity") == array(again.outputs, "velocity"));
    }
}

TEST_CASE("checkpoint -> init(state) resumes bit-identically") {
    for (const char* formulation : {"linear", "corotational"}) {
        Value scene = coupled_scene(formulation);
        StructureSolver a;
        a.init(request(scene));
        Progress p;
        double t = 0;
        for (int k = 0; k < 5; ++k) t = a.advance(window(t, 1e-3, 2, forces(a, 40.0 + k)), p).t;
        const auto blob = a.checkpoint();

        StructureSolver b;
        b.init(request(scene, blob, t));  // as the coordinator resumes: at its checkpoint's time
        for (int k = 0; k < 5; ++k) {
            const AdvanceReply ra = a.advance(window(t, 1e-3, 2, forces(a, 60.0 - k)), p);
            const AdvanceReply rb = b.advance(window(t, 1e-3, 2, forces(b, 60.0 - k)), p);
            t = ra.t;
            CHECK(ra.t == rb.t);
            CHECK(array(ra.outputs, "displacement") == array(rb.outputs, "displacement"));
        }
        const Fields sa = a.snapshot(), sb = b.snapshot();
        CHECK(array(sa, "displacement") == array(sb, "displacement"));
        CHECK(array(sa, "velocity") == array(sb, "velocity"));
        CHECK(array(sa, "energy") == array(sb, "energy"));

        // A checkpoint of another mesh is refused.
        Value other = scene;
        set(other.as_table_mut()["members"].as_array_mut()[0], "n_elements", Value(11));
        StructureSolver c;
        CHECK(code_of([&] { c.init(request(other, blob, t)); }) == "bad_config");
    }
}

// A damaged state: a NaN had gone out in READY's interface state, t = inf passed every later time check (the
// run completed), and a state at another time than INIT's t0 made the first FRAME and ADVANCE disagree about
// where the run was (a review, 2026-11-27). Layout (checkpoint.cpp): the 25-byte tag, dofs, elements,
// fingerprint, t, step, external work (8 bytes each), then u, v, a.
TEST_CASE("a damaged or mistimed checkpoint is refused") {
    Value scene = coupled_scene("linear");
    StructureSolver a;
    a.init(request(scene));
    Progress p;
    const double t = a.advance(window(0.0, 1e-3, 2, forces(a, 40.0)), p).t;
    const auto blob = a.checkpoint();
    auto message_of = [&](std::vector<std::uint8_t> bytes, double t0) -> std::string {
        StructureSolver b;
        try {
            b.init(request(scene, std::move(bytes), t0));
        } catch (const SolverError& e) {
            return e.code() + ": " + e.what();
        }
        return "accepted";
    };
    REQUIRE(message_of(blob, t) == "accepted");
    CHECK(message_of(blob, 0.5).rfind("bad_config: structure: the checkpoint's state is at t = ", 0) == 0);
    // After the magic (25 bytes) and the counts and fingerprint (24): t, step, load work, initial energy, energy
    // scale, u.
    const std::size_t t_at = 25 + 24, initial_at = t_at + 24, scale_at = t_at + 32, u_at = t_at + 40;
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -1.0})
        for (const std::size_t at : {t_at, t_at + 16, initial_at, scale_at, u_at, u_at + 8}) {
            if (bad == -1.0 && at != scale_at && at != initial_at) continue;  // energies cannot be negative
            CAPTURE(at);
            CAPTURE(bad);
            std::vector<std::uint8_t> damaged = blob;
            std::memcpy(damaged.data() + at, &bad, sizeof bad);
            const std::string msg = message_of(damaged, t);
            CHECK(msg.find("not a finite number") != std::string::npos);
            CHECK(msg.find("the file is damaged") != std::string::npos);
        }
    // A clamped node displaced, moving or accelerating: finite numbers no run holds (a review, 2026-11-27).
    for (const std::size_t at : {u_at, u_at + 8 * 33, u_at + 8 * 66 + 8}) {
        CAPTURE(at);
        std::vector<std::uint8_t> damaged = blob;
        const double moved = 0.5;
        std::memcpy(damaged.data() + at, &moved, sizeof moved);
        CHECK(message_of(damaged, t).find("bad_config: structure: the checkpoint gives node 0 a") == 0);
    }
    // A roller on a slanted surface: a run's own v and a carry round-off off the surface, 1/(beta h^2) times
    // u's, and its checkpoint must still be taken (the first version of the check refused it at t = 2.5 s, a
    // review, 2026-11-27).
    Value slanted = beam(20, "clamped", "roller");
    sphfsi::set_path(slanted, "supports[1].normal", vec(0.3, 1.0));
    sphfsi::set_path(slanted, "point_loads", Value(Value::Array{point_load(L / 2, 0.0, 0.0, -100.0)}));
    sphfsi::set_path(slanted, "time.integrator", Value("newmark"));
    sphfsi::set_path(slanted, "damping", table({{"model", Value("rayleigh")}, {"ratios", Value(Value::Array{Value(0.02), Value(0.02)})}}));
    StructureSolver c;
    c.init(request(slanted));
    double tc = 0.0;
    for (int k = 0; k < 5; ++k) tc = c.advance(window(tc, 0.5, 1000, forces(c, 0.0)), p).t;  // settled by 2.5 s
    const auto& T = c.dynamics().model().T;
    const Vector& v = c.dynamics().state().v;
    CHECK((v - T * (T.transpose() * v)).norm() > 0.0);  // the case does hold round-off off the surface
    StructureSolver d;
    CHECK(code_of([&] { d.init(request(slanted, c.checkpoint(), tc)); }) == "none");
    // Versions 1 (no energies, before 2026-11-27) and 2 (the scale alone, the same day) are still read.
    std::vector<std::uint8_t> v2 = blob, v1 = blob;
    REQUIRE(blob[24] == '3');
    v2.erase(v2.begin() + static_cast<std::ptrdiff_t>(initial_at), v2.begin() + static_cast<std::ptrdiff_t>(initial_at + 8));
    v2[24] = '2';
    CHECK(message_of(v2, t) == "accepted");
    v1.erase(v1.begin() + static_cast<std::ptrdiff_t>(initial_at), v1.begin() + static_cast<std::ptrdiff_t>(initial_at + 16));
    v1[24] = '1';
    CHECK(message_of(v1, t) == "accepted");
}

TEST_CASE("a resumed run checks energy against the run's own start, not the resume time's") {
    // Started in static equilibrium under a tip load that varies in time (a sine starting at its crest), the
    // initial energy depends on t0. A review found a resume's INIT rebuilding it at the resume time: the
    // resumed run stopped at its first step as creating 0.5 of its energy scale. The baseline now travels in
    // the checkpoint: resumed, the run goes on exactly as the uninterrupted one.
    Value scene = coupled_scene("linear");
    set(scene, "damping.model", Value("none"));
    set(scene, "initial.static_equilibrium", Value(true));
    Value load = point_load(L, 0.0, 0.0, -100.0);
    load.as_table_mut()["history"] = Value("sine");
    load.as_table_mut()["phase"] = Value(std::numbers::pi / 2);
    load.as_table_mut()["frequency"] = Value(5.0);
    set(scene, "point_loads", Value(Value::Array{load}));
    StructureSolver a;
    a.init(request(scene));
    Progress p;
    const auto zero = forces(a, 0.0);
    double t = 0.0;
    for (int k = 0; k < 50; ++k) t = a.advance(window(t, 1e-3, 1, zero), p).t;  // to 0.05 s, a quarter period
    const auto blob = a.checkpoint();
    StructureSolver b;
    b.init(request(scene, blob, t));
    for (int k = 0; k < 50; ++k) {
        const auto ra = a.advance(window(t, 1e-3, 1, zero), p);
        const auto rb = b.advance(window(t, 1e-3, 1, zero), p);  // threw "energy created" before
        t = ra.t;
        REQUIRE(rb.t == ra.t);
    }
    CHECK(a.dynamics().state().u == b.dynamics().state().u);
}

TEST_CASE("a resume does not redo the scene's start at the resume time") {
    // A free beam in static equilibrium at t = 0, where its tip load has not started yet. At the resume time
    // the load is on, and a free beam under a load has no static equilibrium: INIT of the resume rebuilt the
    // start there and refused the checkpoint ("the structure can move without deforming"), although the
    // run had started fine (a review, 2026-11-27). The resumed run now goes on exactly as the uninterrupted one.
    Value scene = beam(10, "", "", "corotational");
    set(scene, "time.dt_max", Value(1e-3));
    set(scene, "initial.static_equilibrium", Value(true));
    Value load = point_load(L, 0.0, 0.0, -100.0);
    load.as_table_mut()["start_time"] = Value(0.002);
    set(scene, "point_loads", Value(Value::Array{load}));
    StructureSolver a;
    a.init(request(scene));
    Progress p;
    double t = 0.0;
    for (int k = 0; k < 4; ++k) t = a.advance(window(t, 1e-3, 1), p).t;
    StructureSolver b;
    CHECK(code_of([&] { b.init(request(scene, a.checkpoint(), t)); }) == "none");
    for (int k = 0; k < 4; ++k) {
        const double ta = a.advance(window(t, 1e-3, 1), p).t;
        REQUIRE(b.advance(window(t, 1e-3, 1), p).t == ta);
        t = ta;
    }
    CHECK(a.dynamics().state().u == b.dynamics().state().u);
    CHECK(a.dynamics().state().u.norm() > 0.0);
}

TEST_CASE("a sine load's period is resolved by the step the structure asks for") {
    // A tip load at the frequency whose samples at the unloaded beam's step are those of a load at the first
    // natural frequency, f = 1/dt - f1, aliased onto resonance: before 2026-11-27 the structure asked for
    // that step whatever its loads, and the beam swung as if driven at f1 (a review: 5.403e-3 m after 0.5 s
    // at 16.71 Hz and at 5863.29 Hz alike). Now the step resolves the load's period with steps_per_period
    // (20) steps, and the response stays that of a load far above the modes the load excites: from rest, the
    // first mode's free swing is about the static deflection times f1/f (0.0029 here; measured 0.0035), so
    // the bound is 1 % of the static deflection P L^3 / (3 EI). The aliased run reached 1.78 times it by 0.1 s.
    Value scene = coupled_scene();
    set(scene, "damping.model", Value("none"));
    StructureSolver unloaded;
    const InitReply plain = unloaded.init(request(scene));
    const double f1 = plain.info.at("natural_frequencies_hz").at("mode_1").as_double();
    const double f = 1.0 / plain.dt_wanted - f1;
    const double P = 100.0, statics = P * L * L * L / (3 * EI);
    Value load = point_load(L, 0.0, 0.0, -P);
    load.as_table_mut()["history"] = Value("sine");
    load.as_table_mut()["frequency"] = Value(f);
    set(scene, "point_loads", Value(Value::Array{load}));
    StructureSolver s;
    const InitReply r = s.init(request(scene));
    CHECK(r.dt_wanted <= 1.0 / (20 * f) * (1 + 1e-12));
    Progress p;
    double t = 0.0, dt = r.dt_wanted, tip = 0.0;
    const auto quiet = forces(s, 0.0);
    while (t < 0.1) {
        const AdvanceReply a = s.advance(window(t, dt, 1, quiet), p);
        t = a.t;
        dt = a.dt_wanted;
        tip = std::max(tip, std::abs(s.dynamics().state().u[3 * 10 + 1]));
    }
    MESSAGE("load at " << f << " Hz (f1 = " << f1 << " Hz): largest tip deflection " << tip / statics << " of the static one");
    CHECK(tip < 0.01 * statics);
}

TEST_CASE("snapshot fields") {
    StructureSolver s;
    s.init(request(coupled_scene()));
    Progress p;
    s.advance(window(0.0, 1e-3, 1, forces(s, 100.0)), p);
    const Fields f = s.snapshot();
    CHECK(array(f, "nodes").shape == std::vector<std::uint64_t>{11, 2});
    CHECK(array(f, "displacement").shape == std::vector<std::uint64_t>{11, 3});
    CHECK(array(f, "velocity").shape == std::vector<std::uint64_t>{11, 3});
    CHECK(std::get<I32Array>(f.at("elements")).shape == std::vector<std::uint64_t>{10, 2});
    const F64Array& e = array(f, "energy");
    CHECK(e.shape == std::vector<std::uint64_t>{1, 3});
    CHECK(e(0, 0) > 0);
    CHECK(e(0, 1) > 0);
    CHECK(e(0, 2) > 0);
}

TEST_CASE("energies go on the wire per metre of depth, like every 2D quantity") {
    // A slab twice as deep is twice as stiff and heavy and takes twice the force from the same fluid pressure
    // (N/m times depth): it moves the same, and its energies per metre of depth are the same. Before
    // 2026-11-25 they were the slab's totals, which the coordinator added to the fluid's J/m.
    auto run = [](double depth) {
        Value scene = coupled_scene();
        set(scene, "section.depth", Value(depth));
        StructureSolver s;
        s.init(request(scene));
        Progress p;
        AdvanceReply r;
        double t = 0;
        for (int k = 0; k < 5; ++k) t = (r = s.advance(window(t, 1e-3, 2, forces(s, 50.0)), p)).t;
        return std::make_pair(r, s.snapshot());
    };
    const auto [one, frame_one] = run(1.0);
    const auto [two, frame_two] = run(2.0);
    const F64Array &da = array(one.outputs, "displacement"), &db = array(two.outputs, "displacement");
    for (std::size_t i = 0; i < da.values.size(); ++i) CHECK(db.values[i] == doctest::Approx(da.values[i]).epsilon(1e-9));
    for (const char* name : {"kinetic_energy", "strain_energy", "external_work"}) {
        const double a = one.stats.at(name).as_double(), b = two.stats.at(name).as_double();
        CHECK(a > 0);
        CHECK(b == doctest::Approx(a).epsilon(1e-9));
    }
    for (std::size_t k = 0; k < 3; ++k)
        CHECK(array(frame_two, "energy")(0, k) == doctest::Approx(array(frame_one, "energy")(0, k)).epsilon(1e-9));
}

TEST_CASE("errors carry the protocol's codes") {
    Value bad = coupled_scene();
    set(bad, "material.E", Value(-1.0));
    StructureSolver s;
    CHECK(code_of([&] { s.init(request(bad)); }) == "bad_config");
    Value boundless = coupled_scene();  // an infinite start turned the energy check off (inf - inf), silently
    set(boundless, "initial.mode", Value(1));
    set(boundless, "initial.mode_amplitude", Value(1e200));
    CHECK(code_of([&] { s.init(request(boundless)); }) == "bad_config");

    s.init(request(coupled_scene()));
    Progress p;
    CHECK(code_of([&] { s.advance(window(0.5, 1e-3, 1), p); }) == "bad_state");  // wrong window start (docs/protocol.md)
    {  // More sub-steps than a uint32 holds: the count used to wrap to a few huge steps, silently.
        Value tiny = coupled_scene();
        set(tiny, "time.dt_max", Value(2.3283064338e-12));  // 1e-2 s / this = 4.3e9 > 2^32 - 1
        StructureSolver t;
        t.init(request(tiny));
        CHECK(code_of([&] { t.advance(window(0.0, 1e-2, 0), p); }) == "bad_message");
    }
    // Inputs and windows it cannot take are refused before any step, as the protocol's codes say (a review,
    // 2026-11-27: a NaN force was "diverged", a window of 1e-300 s an "internal" singular matrix).
    Fields nan = forces(s, 1.0);
    std::get<F64Array>(nan["force"])(3, 0) = std::nan("");
    CHECK(code_of([&] { s.advance(window(0.0, 1e-3, 1, nan), p); }) == "bad_message");
    CHECK(code_of([&] { s.advance(window(0.0, 1e-300, 1), p); }) == "bad_message");
    CHECK(s.dynamics().state().t == 0.0);
    F64Array huge = F64Array::zeros(22, 2);
    huge(21, 1) = 1e300;
    try {
        s.advance(window(0.0, 1e-3, 1, Fields{{"force", huge}}), p);
        FAIL("expected diverged");
    } catch (const SolverError& e) {
        // The displacement it names is the finite one it found (its norm used to overflow to "inf"), at the
        // time the step ends, as the other step failures say.
        const std::string what = e.what();
        MESSAGE(what);
        CHECK(e.code() == "diverged");
        CHECK(what.find(" is inf") == std::string::npos);
        CHECK(what.find("step 1, t=0.001;") != std::string::npos);
    }

    Value stiff = coupled_scene("corotational");
    set(stiff, "newton.max_iterations", Value(2));
    StructureSolver c;
    c.init(request(stiff));
    CHECK(code_of([&] { c.advance(window(0.0, 0.05, 1, forces(c, 5000.0)), p); }) == "not_converged");
}

TEST_CASE("structure alone: a slowly ramped tip load settles on the static deflection P L^3 / (3 EI)") {
    // Standalone run under the scene's own time-varying load: ramp over 2 s, heavy Rayleigh damping
    // (20 %), run to 4 s. Cubic elements are exact at the nodes for a tip load, and what the ramp leaves
    // swinging (about 1 % at omega T = 105) decays for 2 s at 20 % damping, by exp(-0.2 x 52.5 x 2) = 1e-9:
    // tolerance 1e-6 (measured below printing precision).
    Value s = beam(10);
    Value load = point_load(L, 0, 0, -500.0);
    set(load, "history", Value("ramp"));
    set(load, "ramp_time", Value(2.0));
    set(s, "point_loads", Value(Value::Array{load}));
    set(s, "damping.model", Value("rayleigh"));
    set(s, "damping.ratios", vec(0.2, 0.2));
    set(s, "members", Value(Value::Array{table({{"start", vec(0, 0)}, {"end", vec(L, 0)}, {"n_elements", Value(10)},
                                                {"wetted", Value(false)}})}));
    set(s, "time.dt_max", Value(5e-3));
    StructureSolver solver;
    const InitReply r = solver.init(request(s));
    CHECK(!r.interface);  // nothing wetted: no interface to publish
    Progress p;
    double t = 0;
    while (t < 4.0 - 1e-9) t = solver.advance(window(t, 0.1, 0), p).t;
    const double tip = std::get<F64Array>(solver.snapshot().at("displacement"))(10, 1);
    const double want = -500.0 * L * L * L / (3 * EI);
    MESSAGE("tip " << tip << " vs static " << want << ", relative error " << rel(tip, want));
    CHECK(rel(tip, want) <= 1e-6);
}

TEST_CASE("a window reports the largest Newton residual its steps ended on") {
    // Newton stops at newton.tolerance (1e-8) of the force scale, or on its round-off floor at up to
    // sqrt(tolerance): the record shows which (docs/record.md). (Linear steps solve exactly and report 0.)
    StructureSolver s;
    s.init(request(coupled_scene("corotational")));
    Progress p;
    const AdvanceReply r = s.advance(window(0.0, 1e-3, 2, forces(s, 500.0)), p);
    const double residual = r.stats.at("newton_residual_max").as_double();
    MESSAGE("largest relative residual " << residual);
    CHECK((residual > 0.0 && residual <= 1e-4));
}
}
