#include "sphfsi/fluid/sph_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include <omp.h>

#include "sphfsi/fluid/gate.hpp"
#include "sphfsi/fluid/schema.hpp"

namespace sphfsi::fluid {
namespace {

// The participant's checkpoint opens with "SPHFSIP2" (little-endian u64). Checkpoints of builds before
// 2026-11-26 opened with the simulation state itself ("SPHFSIF1") and lack the start displacement: refused as
// written by an older build. Those of the builds of 2026-11-26/27 between commits 1244f65 and d6467fe opened
// with the displacement's length and are refused as not a sphfsi-fluid checkpoint.
constexpr std::uint64_t checkpoint_magic = 0x3350495346485053ULL;         // "SPHFSIP3": with the correction L
constexpr std::uint64_t checkpoint_magic_p2 = 0x3250495346485053ULL;      // "SPHFSIP2": without it, still read
constexpr std::uint64_t older_checkpoint_magic = 0x3146495346485053ULL;   // "SPHFSIF1"

using protocol::F64Array;
using protocol::I32Array;
using protocol::SolverError;

// Distance from p to a quadrilateral cell (counter-clockwise; convex cells, as a beam mesh has); 0 inside.
double distance_to_quad(const std::array<Vec2, 4>& q, const Vec2& p) {
    bool inside = true;
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 4; ++k) {
        const Vec2 a = q[static_cast<std::size_t>(k)], b = q[static_cast<std::size_t>((k + 1) % 4)];
        const double ex = b[0] - a[0], ey = b[1] - a[1], px = p[0] - a[0], py = p[1] - a[1];
        if (ex * py - ey * px < 0.0) inside = false;
        const double len2 = ex * ex + ey * ey;
        const double s = len2 > 0.0 ? std::clamp((px * ex + py * ey) / len2, 0.0, 1.0) : 0.0;
        nearest = std::min(nearest, std::hypot(px - s * ex, py - s * ey));
    }
    return inside ? 0.0 : nearest;
}

// The structure's mesh, in its reference position, must lie in the tank, walls included (a plate's ends may
// sit in the side walls). Elsewhere its solid particles would be outside every wall, and the neighbour grid,
// which spans all particles, would grow with the distance: a mesh 1e6 m away took gigabytes before a step.
// A periodic axis has no walls, and the mesh must lie within its period: solid particles go where the
// structure puts them, never wrapped, so one across the seam would sit a period away from the water it meets
// there in every rate that wraps positions (a review, 2026-11-27).
// `position(v)` is vertex v's position; `code` and `why` say whose fault it is.
template <class Position>
void check_inside_tank(std::uint64_t vertices, Position position, const FluidSettings& s, const char* where,
                       const char* code, const char* why) {
    const double wall = s.wall_layers * s.dp;
    const double x_wall = s.periodic[0] ? 0.0 : wall, y_wall = s.periodic[1] ? 0.0 : wall;
    const double x_lo = -x_wall, x_hi = s.tank_width + x_wall, y_lo = -y_wall, y_hi = s.tank_height + y_wall;
    for (std::uint64_t v = 0; v < vertices; ++v) {
        const auto [x, y] = position(v);
        if (!(x >= x_lo && x <= x_hi && y >= y_lo && y <= y_hi)) {
            char buf[480];
            std::snprintf(buf, sizeof buf,
                          "the structure's interface mesh has vertex %llu at (%.6g, %.6g) m%s, outside the tank and its walls "
                          "(x in [%.6g, %.6g], y in [%.6g, %.6g] m%s): %s",
                          static_cast<unsigned long long>(v), x, y, where, x_lo, x_hi, y_lo, y_hi,
                          s.periodic[0] || s.periodic[1] ? ", a periodic axis's period alone" : "", why);
            throw SolverError(code, buf);
        }
    }
}

void check_inside_tank(const protocol::InterfaceMesh& mesh, const FluidSettings& s, const char* where = "") {
    check_inside_tank(mesh.vertices.rows(), [&](std::uint64_t v) { return std::pair{mesh.vertices(v, 0), mesh.vertices(v, 1)}; },
                      s, where, "bad_config", "fluid.tank and the structure's geometry disagree");
}

const F64Array* find_f64(const protocol::Fields& fields, const char* name) {
    auto it = fields.find(name);
    if (it == fields.end()) return nullptr;
    const auto* a = std::get_if<F64Array>(&it->second);
    if (!a) throw SolverError("bad_message", std::string("input '") + name + "' must be f8");
    return a;
}

void write_coupling_state(ByteWriter& w, const InterfaceCoupling::State& s) {
    w.put_vector(s.u0); w.put_vector(s.v0); w.put_vector(s.u1); w.put_vector(s.v1);
    w.put(s.t0); w.put(s.dt);
}

// The window state a resume restores: per-vertex arrays of the mesh's size, finite, and a window of length
// >= 0 (0 between windows).
void check_coupling_state(const InterfaceCoupling::State& s, std::size_t vertices) {
    for (const auto& [a, name] : {std::pair{&s.u0, "start displacement"}, {&s.v0, "start velocity"},
                                  {&s.u1, "end displacement"}, {&s.v1, "end velocity"}}) {
        if (a->size() != vertices)
            throw SolverError("bad_config", std::string("checkpoint: its interface window's ") + name + " has " +
                                                std::to_string(a->size()) + " vertices, this INIT's mesh " +
                                                std::to_string(vertices) + ": resume with the scene that wrote it");
        for (const Vec2& x : *a)
            if (!std::isfinite(x[0]) || !std::isfinite(x[1]))
                throw SolverError("bad_config", std::string("checkpoint: its interface window's ") + name + " is not finite");
    }
    if (!std::isfinite(s.t0) || !(s.dt >= 0.0) || !std::isfinite(s.dt))
        throw SolverError("bad_config", "checkpoint: its interface window (t0 = " + protocol::seconds(s.t0) +
                                            ", dt = " + protocol::seconds(s.dt) + ") is not a finite time and length >= 0");
}

InterfaceCoupling::State read_coupling_state(ByteReader& r) {
    InterfaceCoupling::State s;
    r.get_vector(s.u0); r.get_vector(s.v0); r.get_vector(s.u1); r.get_vector(s.v1);
    s.t0 = r.get<double>();
    s.dt = r.get<double>();
    return s;
}

}  // namespace

const schema::TableSchema& SphSolver::schema() const { return scene_schema(); }

void SphSolver::require_init() const {
    if (!sim_) throw SolverError("internal", "the fluid solver was used before INIT");
}

protocol::InitReply SphSolver::init(const protocol::InitRequest& request) {
    try {
        settings_ = read_settings(request.config);
    } catch (const ConfigError& e) {
        throw SolverError("bad_config", e.what());
    }
    sim_ = std::make_unique<Simulation2D>(settings_, build_scene(settings_), request.t0);
    coupling_.reset();
    if (settings_.gate) {
        // One set of solid particles per fluid: a gate's motion is prescribed, a structure's is not.
        if (request.interface)
            throw SolverError("bad_config", "fluid.gate: a scene with a gate cannot also couple a structure "
                                            "(one set of solid particles per fluid); remove [fluid.gate] or the structure");
        const Gate g = *settings_.gate;
        const GateLift lift{g.lift_speed, g.height};
        auto reference = gate_particles(settings_);
        sim_->add_solids(
            reference, reference,
            [reference, lift](std::size_t k, double t, Vec2& x, Vec2& v, Vec2& a) {
                double dy = 0.0, vy = 0.0;
                lift.at(t, dy, vy);
                x = Vec2{{reference[k][0], reference[k][1] + dy}};
                v = Vec2{{0.0, vy}};
                a = Vec2{};
            },
            [g](const Vec2& p) { return p[0] > g.x0 && p[0] < g.x0 + g.thickness && p[1] < g.height; });
        const std::vector<Vec2> corners{Vec2{{g.x0, 0.0}}, Vec2{{g.x0 + g.thickness, 0.0}},
                                        Vec2{{g.x0 + g.thickness, g.height}}, Vec2{{g.x0, g.height}}};
        sim_->set_solid_section("the gate", {{0, 1, 2, 3}}, corners, [corners, lift](double t, std::vector<Vec2>& out) {
            double dy = 0.0, vy = 0.0;
            lift.at(t, dy, vy);
            out = corners;
            for (Vec2& c : out) c[1] += dy;
        });
    }
    // A checkpoint opens with the interface displacement the run started from (empty: undeformed): a resume
    // clears the water around the structure where the first start did, so it lays out the same particles.
    std::optional<ByteReader> saved;
    if (!request.state.empty()) {
        saved.emplace(request.state);
        try {
            const auto magic = saved->get<std::uint64_t>();
            if (magic == older_checkpoint_magic)
                throw SolverError("bad_config", "checkpoint: written by an older build of sphfsi-fluid (format SPHFSIF1, "
                                                "before the start displacement was saved); this build cannot resume it: "
                                                "start the run afresh, or resume with the build that wrote it");
            if (magic != checkpoint_magic && magic != checkpoint_magic_p2)
                throw SolverError("bad_config", "checkpoint: not a sphfsi-fluid checkpoint");
            state_has_correction_ = magic == checkpoint_magic;
            saved->get_vector(start_displacement_);
        } catch (const SolverError&) {
            throw;
        } catch (const std::runtime_error& e) {
            throw SolverError("bad_config", e.what());
        }
    } else {
        const F64Array* u0 = find_f64(request.interface_state, "displacement");
        start_displacement_ = u0 ? u0->values : std::vector<double>{};
    }
    if (request.interface) {
        if (request.interface->cells.rows() == 0)  // READY with no solid particle: a coupling that did nothing
            throw SolverError("bad_config", "the interface mesh has no cells: the fluid would feel no structure");
        check_inside_tank(*request.interface, settings_);
        try {
            coupling_.emplace(*request.interface, settings_.dp);
        } catch (const std::invalid_argument& e) {
            throw SolverError("bad_config", e.what());
        }
        // Protocol 2: the structure may start deformed or moving (absent: undeformed, at rest).
        for (const auto& [name, field] : request.interface_state)
            if (name != "displacement" && name != "velocity")
                throw SolverError("bad_message", "INIT interface_state has the field '" + name +
                                                     "'; allowed: displacement, velocity");
        const F64Array* u0 = find_f64(request.interface_state, "displacement");
        const F64Array* v0 = find_f64(request.interface_state, "velocity");
        InterfaceCoupling* coupling = &*coupling_;
        try {
            coupling->begin_window(request.t0, 0.0, u0, v0);
        } catch (const std::invalid_argument& e) {
            throw SolverError("bad_message", std::string("INIT interface_state: ") + e.what());
        }
        coupling->end_window();
        // Where the structure starts, too: a deflected start (INIT's interface_state) 5 m above a 0.4 m tank was
        // accepted (a review, 2026-11-27).
        // A fresh start only: a resume's interface_state is where the run had got to, which every window's
        // end was checked against (advance).
        if (u0 && request.state.empty() && u0->values.size() == 2 * request.interface->vertices.rows()) {
            protocol::InterfaceMesh started = *request.interface;
            for (std::size_t i = 0; i < started.vertices.values.size(); ++i) started.vertices.values[i] += u0->values[i];
            check_inside_tank(started, settings_, " where it starts (reference plus INIT's interface_state displacement)");
        }
        // Water is cleared from the structure where it stood at the start, and from within dp/2 of its faces (at
        // least dp from its solid particles, which sit dp/2 inside): a lattice laid against a face keeps its first
        // row at exactly dp/2, but a structure that starts deflected into the water would otherwise meet particles
        // at a fraction of dp from its solid particles, which blew the first step up (elastic gate, mode-1 start).
        const double clearance = 0.5 * settings_.dp * (1.0 - 1e-9);
        const auto& mesh = *request.interface;
        if (!start_displacement_.empty() && start_displacement_.size() != 2 * mesh.vertices.rows())
            throw SolverError("bad_config", "checkpoint: its start displacement has " +
                                                std::to_string(start_displacement_.size()) + " values for the mesh's " +
                                                std::to_string(mesh.vertices.rows()) + " vertices (two each)");
        for (double u : start_displacement_)
            if (!std::isfinite(u)) throw SolverError("bad_config", "checkpoint: its start displacement is not finite");
        auto start = [&](std::uint64_t v, int axis) {
            const double u = start_displacement_.empty() ? 0.0 : start_displacement_[2 * v + static_cast<std::uint64_t>(axis)];
            return mesh.vertices(v, static_cast<std::uint64_t>(axis)) + u;
        };
        std::vector<std::array<Vec2, 4>> quads;
        for (std::size_t c = 0; c < mesh.cells.rows(); ++c) {
            std::array<Vec2, 4> q;
            for (int k = 0; k < 4; ++k) {
                const auto v = static_cast<std::uint64_t>(mesh.cells(c, static_cast<std::uint64_t>(k)));
                q[static_cast<std::size_t>(k)] = Vec2{{start(v, 0), start(v, 1)}};
            }
            quads.push_back(q);
        }
        const std::size_t fluid_before = sim_->fluid_count();
        sim_->add_solids(
            coupling->reference_positions(), coupling->displaced_positions(start_displacement_),  // as the cells
            [coupling](std::size_t k, double t, Vec2& x, Vec2& v, Vec2& a) { coupling->kinematics(k, t, x, v, a); },
            [quads, clearance](const Vec2& p) {
                for (const auto& q : quads) {
                    bool near_box = true;  // cheap test first: a fluid particle is near few of the cells
                    for (int axis = 0; axis < 2; ++axis) {
                        const auto [lo, hi] = std::minmax({q[0][axis], q[1][axis], q[2][axis], q[3][axis]});
                        near_box = near_box && p[axis] > lo - clearance && p[axis] < hi + clearance;
                    }
                    if (near_box && distance_to_quad(q, p) < clearance) return true;
                }
                return false;
            });
        // A structure laid over all the water leaves a run that completes and means nothing (a review: a plate
        // 0.1 m thick over the whole column ended "completed" with no fluid).
        if (sim_->fluid_count() == 0 && fluid_before > 0)
            throw SolverError("bad_config", "the structure's wetted cross-section covers all " + std::to_string(fluid_before) +
                                                " water particles (they are cleared within dp/2 of it): fluid.water and the "
                                                "structure's geometry disagree");
        std::vector<SolidSection::Quad> cells(mesh.cells.rows());
        for (std::size_t c = 0; c < cells.size(); ++c)
            for (std::size_t k = 0; k < 4; ++k) cells[c][k] = mesh.cells(c, static_cast<std::uint64_t>(k));
        sim_->set_solid_section("the structure", std::move(cells), coupling->vertex_reference(),
                                [coupling](double t, std::vector<Vec2>& out) { coupling->vertex_positions(t, out); });
    }
    if (saved) {
        try {
            ByteReader& r = *saved;
            sim_->read_state(r, state_has_correction_);
            const auto coupling_flag = r.get<std::uint8_t>();
            if (coupling_flag > 1)
                throw SolverError("bad_config", "checkpoint: its interface flag is " + std::to_string(coupling_flag) + ", not 0 or 1");
            const bool has_coupling = coupling_flag != 0;
            if (has_coupling != coupling_.has_value())
                throw SolverError("bad_config", "checkpoint: it was written " + std::string(has_coupling ? "with" : "without") +
                                                    " an interface mesh, but this INIT " +
                                                    (coupling_ ? "has one" : "has none"));
            if (coupling_) {
                const InterfaceCoupling::State state = read_coupling_state(r);
                check_coupling_state(state, coupling_->vertex_count());
                coupling_->set_state(state);
            }
            if (!r.at_end()) throw SolverError("bad_config", "checkpoint: trailing bytes");
            // INIT's t0 is the coordinator's checkpoint time; the state carries its own. They must be one instant,
            // or the first FRAME and ADVANCE would disagree about where the run is.
            if (!protocol::same_instant(sim_->time(), request.t0, 0.0))
                throw SolverError("bad_config", "checkpoint: its state is at t = " + protocol::seconds(sim_->time()) +
                                                    ", but INIT resumes at t0 = " + protocol::seconds(request.t0));
        } catch (const std::runtime_error& e) {
            if (dynamic_cast<const SolverError*>(&e)) throw;
            throw SolverError("bad_config", e.what());
        }
    }
    // No SAVE here: the saved copy is a second full particle state (about 100 bytes per particle), and only
    // implicit coupling, which SAVEs at every window start, ever restores one.
    protocol::InitReply reply;
    // A floor already reached at the start is the first ADVANCE's failure, as at a window's end: the start is
    // whole and becomes the record's t0 frame (INIT had thrown, and the record kept no frame; a kill probe).
    reply.dt_wanted = next_step_wanted();
    Value::Table info;
    info["particles"] = Value(static_cast<std::int64_t>(sim_->particles().size()));
    info["fluid_particles"] = Value(static_cast<std::int64_t>(sim_->fluid_count()));
    info["wall_particles"] = Value(static_cast<std::int64_t>(sim_->wall_count()));
    info["solid_particles"] = Value(static_cast<std::int64_t>(sim_->solid_count()));
    info["dp"] = Value(settings_.dp);
    info["h"] = Value(sim_->h());
    info["support_radius"] = Value(sim_->support());
    info["particle_mass"] = Value(sim_->mass());
    info["rho0"] = Value(settings_.rho0);  // the reference density the record's density errors are taken against
    info["c0"] = Value(sim_->c0());
    info["pressure_model"] = Value(to_string(settings_.pressure));
    info["density_method"] = Value(to_string(settings_.density));
    info["viscosity_model"] = Value(to_string(settings_.viscosity));
    info["wall_model"] = Value(to_string(settings_.wall));
    info["integrator"] = Value(to_string(settings_.integrator));
    info["threads"] = Value(static_cast<std::int64_t>(sim_->threads()));
    info["memory_bytes_per_particle"] =
        Value(static_cast<double>(sim_->memory_bytes()) / static_cast<double>(sim_->particles().size()));
    reply.info = Value(std::move(info));
    return reply;
}

protocol::AdvanceReply SphSolver::advance(const protocol::AdvanceRequest& request, protocol::Progress& progress) {
    require_init();
    const double t = sim_->time();
    protocol::check_window(request, t, "fluid");
    if (step_floor_failure_) throw *step_floor_failure_;
    if (coupling_) {
        // Where the window ends must be in the tank too, checked before the window's state takes anything in
        // (a refused window changes nothing): a structure moved 1e6 m away was taken, its solid particles then
        // outside every wall (a review, 2026-11-28). The path within the window is an interpolation between
        // two checked ends; it is not checked again.
        const F64Array* displacement = find_f64(request.inputs, "displacement");
        const auto& reference = coupling_->vertex_reference();
        if (displacement && displacement->rows() == reference.size() && displacement->cols() == 2)
            check_inside_tank(
                reference.size(),
                [&](std::uint64_t v) {
                    return std::pair{reference[v][0] + (*displacement)(v, 0), reference[v][1] + (*displacement)(v, 1)};
                },
                settings_, " at the window's end (reference plus ADVANCE displacement)", "bad_message",
                "the structure answered a position the fluid cannot hold");
        try {
            coupling_->begin_window(t, request.dt, displacement, find_f64(request.inputs, "velocity"));
        } catch (const std::invalid_argument& e) {  // an input of the wrong shape: a bad array size
            throw SolverError("bad_message", e.what());
        }
    }
    const WindowStats ws = sim_->advance(t + request.dt, request.substeps, [&] { progress.tick(); });
    protocol::AdvanceReply reply;
    reply.t = sim_->time();
    reply.substeps = ws.steps;
    reply.solver_iterations = static_cast<std::uint32_t>(ws.iterations);
    if (coupling_)
        reply.outputs["force"] = InterfaceCoupling::map_forces(coupling_->weights(), sim_->mean_solid_forces(),
                                                               coupling_->vertex_count());
    reply.dt_wanted = next_step_wanted();
    if (coupling_) coupling_->end_window();
    Value::Table stats;
    stats["steps"] = Value(static_cast<std::int64_t>(ws.steps));
    stats["dt_min"] = Value(ws.dt_min);
    stats["dt_max"] = Value(ws.dt_max);
    stats["dt_last"] = Value(ws.dt_last);
    stats["max_density_error"] = Value(ws.max_density_error);
    stats["pcisph_iterations"] = Value(static_cast<std::int64_t>(ws.iterations));
    stats["pcisph_max_iterations"] = Value(static_cast<std::int64_t>(ws.max_iterations));
    stats["pcisph_retries"] = Value(static_cast<std::int64_t>(ws.retries));
    stats["max_speed"] = Value(sim_->particles().size() ? sim_->max_speed() : 0.0);
    const auto energy = sim_->mechanical_energy();
    stats["kinetic_energy"] = Value(energy.kinetic);
    stats["potential_energy"] = Value(energy.potential);
    stats["escaped_particles"] = Value(static_cast<std::int64_t>(sim_->escaped_count()));
    stats["free_surface_particles"] = Value(static_cast<std::int64_t>(sim_->free_surface_count()));
    // The surface the wind acted on (m; tau times it is its force), so that a record shows whether the whole
    // surface felt it: the tank's length when every surface particle is found. Only in scenes with wind.
    if (sim_->has_wind()) stats["wind_surface_length"] = Value(sim_->wind_surface());
    // The most fluid particles more than 0.1 dp beyond a tank wall's surface or inside an obstacle, the gate or
    // the structure after any step of the window (Simulation2D::wall_crossings; 0 in a healthy run): makes a
    // leak visible in every record, also one that came back out before the window ended.
    stats["wall_crossings"] = Value(static_cast<std::int64_t>(ws.max_wall_crossings));
    reply.stats = Value(std::move(stats));
    return reply;
}

// docs/protocol.md, ADVANCE: a coupled fluid receives the interface's window-end kinematics, a fluid run
// alone no inputs.
std::optional<std::vector<std::string>> SphSolver::advance_inputs() const {
    if (coupling_) return std::vector<std::string>{"displacement", "velocity"};
    return std::vector<std::string>{};
}

// The step the fluid wants after a window, for its reply. A stable step below the floor is the next step's
// failure, not this window's: the window is whole, so it is answered asking for the floor (and recorded with its
// frame), and the next ADVANCE raises the diagnostic before it steps, whatever its sub-steps. Thrown here, it
// had discarded the finished window and the frame at its end (a review, 2026-11-27).
double SphSolver::next_step_wanted() {
    try {
        return sim_->stable_dt();
    } catch (const SolverError& e) {
        if (e.code() != "diverged") throw;
        step_floor_failure_ = e;
        return settings_.dt_min;
    }
}

void SphSolver::save() {
    require_init();
    sim_->save();
    if (coupling_) saved_coupling_ = coupling_->state();
}

void SphSolver::restore() {
    require_init();
    sim_->restore();
    step_floor_failure_.reset();  // it was the repeated window's end state's
    if (coupling_) coupling_->set_state(saved_coupling_);
}

protocol::Fields SphSolver::snapshot() {
    require_init();
    const auto& P = sim_->particles();
    const std::size_t n = P.size();
    auto pos = F64Array::zeros(n, 2), vel = F64Array::zeros(n, 2);
    auto rho = F64Array::zeros(n, 1), p = F64Array::zeros(n, 1);
    auto tag = I32Array::zeros(n, 1), kind = I32Array::zeros(n, 1), surface = I32Array::zeros(n, 1);
    const float threshold = sim_->surface_threshold();
    for (std::size_t i = 0; i < n; ++i) {
        const auto k = static_cast<std::uint64_t>(P.id[i]);  // stable order: by original index
        pos(k, 0) = P.x[i][0];
        pos(k, 1) = P.x[i][1];
        vel(k, 0) = P.v[i][0];
        vel(k, 1) = P.v[i][1];
        rho(k, 0) = P.rho[i];
        p(k, 0) = P.p[i];
        tag(k, 0) = P.tag[i];
        kind(k, 0) = static_cast<std::int32_t>(P.kind[i]);  // 0 fluid, 1 wall, 2 solid, 3 escaped
        surface(k, 0) = P.kind[i] == Kind::Fluid && P.div_r[i] < threshold ? 1 : 0;
    }
    protocol::Fields f;
    f["position"] = std::move(pos);
    f["velocity"] = std::move(vel);
    f["density"] = std::move(rho);
    f["pressure"] = std::move(p);
    f["tag"] = std::move(tag);
    f["kind"] = std::move(kind);
    f["free_surface"] = std::move(surface);
    return f;
}

std::vector<std::uint8_t> SphSolver::checkpoint() {
    require_init();
    // A failure found at the last window's end (next_step_wanted) is the run's next event: a checkpoint of
    // that state would resume into it without its message (or be refused as damaged, with NaN rates), so the
    // request is answered with the failure itself (a review, 2026-11-27).
    if (step_floor_failure_) throw *step_floor_failure_;
    ByteWriter w;
    w.put(checkpoint_magic);
    w.put_vector(start_displacement_);  // before the particles: a resume lays them out around it (init)
    sim_->write_state(w);
    w.put<std::uint8_t>(coupling_ ? 1 : 0);
    if (coupling_) write_coupling_state(w, coupling_->state());
    return w.take();
}

}  // namespace sphfsi::fluid
