#include "sphfsi/structure/participant.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "sphfsi/structure/checkpoint.hpp"
#include "sphfsi/structure/schema.hpp"

namespace sphfsi::structure {

using namespace sphfsi::protocol;

namespace {
// The model is a slab of depth b (section.depth) and its energies are those of the slab; on the wire, as
// every 2D quantity, they are per metre of depth (docs/protocol.md §4), so that the coordinator's energy
// checks add them to the fluid's J/m.
Energies per_metre_of_depth(const FrameDynamics& d) {
    Energies e = d.energies();
    const double b = d.config().section.depth;
    e.kinetic /= b;
    e.strain /= b;
    e.external_work /= b;
    return e;
}
}  // namespace

const schema::TableSchema& StructureSolver::schema() const { return scene_schema(); }

FrameDynamics& StructureSolver::dyn() {
    if (!dynamics_) throw SolverError("internal", "structure: used before INIT");
    return *dynamics_;
}

InitReply StructureSolver::init(const InitRequest& request) {
    StructureConfig config;
    try {
        config = StructureConfig::from_value(request.config);
    } catch (const ConfigError& e) {
        throw SolverError("bad_config", e.what());
    }
    dynamics_ = std::make_unique<FrameDynamics>(std::move(config), request.t0, request.state.empty());
    if (!request.state.empty()) {
        dynamics_->state() = decode_state(request.state, dynamics_->model());
        // INIT's t0 is the coordinator's checkpoint time, the state carries its own: one instant, or the first
        // FRAME and ADVANCE would disagree about where the run is.
        if (!protocol::same_instant(dynamics_->state().t, request.t0, 0.0))
            throw SolverError("bad_config", "structure: the checkpoint's state is at t = " +
                                                protocol::seconds(dynamics_->state().t) + ", but INIT resumes at t0 = " +
                                                protocol::seconds(request.t0));
    }
    interface_ = std::make_unique<InterfaceMap>(dynamics_->model(), dynamics_->config());
    saved_.reset();
    dt_wanted_ = std::min(dynamics_->config().time.dt_max, dynamics_->dt_accuracy());

    InitReply reply;
    reply.dt_wanted = dt_wanted_;
    if (interface_->vertex_count() > 0) {
        reply.interface = interface_->mesh();
        // A deformed or moving start (structure.initial, or a resumed state) is passed on (protocol 2), so the
        // fluid and the watchpoints see the structure where it is at t0, not undeformed.
        const State& s = dynamics_->state();
        if (!s.u.isZero(0.0) || !s.v.isZero(0.0))
            reply.interface_state = {{"displacement", interface_->displacement(s.u)},
                                     {"velocity", interface_->velocity(s.u, s.v)}};
    }
    const Model& m = dynamics_->model();
    const Modes& modes = dynamics_->modes();
    Value::Table freqs;  // READY info holds numbers, strings, booleans and maps, no arrays
    // The lowest 20 at most: READY info is bounded (256 entries), and initial.mode may ask for many more.
    for (int i = modes.rigid_body; i < std::min<int>(static_cast<int>(modes.omega2.size()), modes.rigid_body + 20); ++i)
        freqs["mode_" + std::to_string(i - modes.rigid_body + 1)] = Value(modes.omega(i) / (2 * std::numbers::pi));
    Value::Table info{{"nodes", Value(m.node_count())},
                      {"elements", Value(static_cast<int>(m.elements.size()))},
                      {"free_dofs", Value(m.free_count())},
                      {"interface_vertices", Value(static_cast<std::int64_t>(interface_->vertex_count()))},
                      {"natural_frequencies_hz", Value(std::move(freqs))},
                      {"dt_accuracy", Value(dynamics_->dt_accuracy())},
                      {"t", Value(dynamics_->state().t)}};
    if (dynamics_->config().damping.kind != DampingKind::None) {
        info["damping_alpha"] = Value(dynamics_->rayleigh_alpha());
        info["damping_beta"] = Value(dynamics_->rayleigh_beta());
    }
    reply.info = Value(std::move(info));
    return reply;
}

AdvanceReply StructureSolver::advance(const AdvanceRequest& request, Progress& progress) {
    FrameDynamics& d = dyn();
    const double t0 = d.state().t;
    protocol::check_window(request, t0, "structure");

    // The sub-steps as runs of equal ones: (end time, step, count). Asked for a count, that many equal ones.
    // Left to choose (substeps 0), the fewest no longer than the step it wants, landing on every time a scene
    // load switches on or off: sampled only at step ends, a pulse shorter than a step between two ends was
    // lost (50 us of 100 kN: the beam never moved; a review, 2026-11-28), and one that ends are placed on
    // is applied whole (FrameDynamics::step).
    struct Run {
        double end, h;
        std::uint32_t count;
    };
    std::vector<Run> runs;
    const auto too_many = [&] {
        return SolverError("bad_message", "structure: a window of " + seconds(request.dt) + " needs more sub-steps of " +
                                              seconds(dt_wanted_) + " than a count can hold (time.dt_max is too small)");
    };
    const double t_end = request.t + request.dt;
    if (request.substeps > 0) {
        runs.push_back({t_end, request.dt / request.substeps, request.substeps});
    } else {
        // A switch within round-off of the window's ends is taken at that end: a sliver of a run there would be
        // a step of 1e-17 s.
        const double sliver = 1e-9 * std::max(std::abs(t_end), request.dt);
        std::vector<double> ends;
        for (double ts : d.load_switch_times())
            if (ts > t0 + sliver && ts < t_end - sliver) ends.push_back(ts);
        ends.push_back(t_end);
        double from = t0;
        for (double to : ends) {
            const auto count = substeps_to_cover(to - from, dt_wanted_);
            if (!count) throw too_many();
            runs.push_back({to, (to - from) / *count, *count});
            from = to;
        }
    }
    std::uint64_t n = 0;
    for (const Run& r : runs) {
        n += r.count;
        // The integrators divide by h^2 (Newmark's 1/(beta h^2)): a sub-step whose square underflows is not
        // one they can take. It was reported as an internal "singular effective matrix" with no step or time.
        if (!std::isfinite(4.0 / (r.h * r.h)))  // 1/beta <= 4 for every integrator here (Newmark and generalized-alpha)
            throw SolverError("bad_message", "structure: a sub-step of " + seconds(r.h) + " is too short to integrate (1/h^2 overflows)");
    }
    if (n > UINT32_MAX) throw too_many();

    const F64Array* force = nullptr;
    if (auto it = request.inputs.find("force"); it != request.inputs.end()) {
        force = std::get_if<F64Array>(&it->second);
        if (!force) throw SolverError("bad_message", "structure: inputs[\"force\"] must be an f8 array");
    }
    const double depth = d.config().section.depth;

    // A fresh start's acceleration balances the loads at t0, and the interface force (the fluid's, or the
    // coordinator's [load]) is one of them: it is first known here. Left out, Newmark treated a force present
    // from t0 as a ramp over the first sub-step, an h/2 delay that made it first order in that response (a
    // [load] against the same scene point loads: 4 % of the peak apart at 20 steps a period; a review,
    // 2026-11-28). step == 0 also after a RESTORE to the start, so each implicit iterate gets its own.
    if (force && d.state().step == 0) d.equilibrate_acceleration(interface_->lump(*force, d.state().u, depth));

    AdvanceReply reply;
    int max_iterations = 0;
    double max_residual = 0.0;  // Newton may stop on its round-off floor, up to sqrt(tolerance): recorded
    for (const Run& run : runs) {
        const double run_start = d.state().t;
        for (std::uint32_t k = 0; k < run.count; ++k) {
            // Moment arms of the vertex forces follow the cross-sections: taken at each sub-step's start.
            const Vector extra = force ? interface_->lump(*force, d.state().u, depth) : Vector();
            // Each step ends where it should, exactly (no drift from summing h): at a load's switch the sum
            // landed a hair past it, and the step before took the load early (a pulse twice its impulse).
            const double t_after = k + 1 == run.count ? run.end : run_start + (k + 1) * run.h;
            const StepReport r = d.step(run.h, extra, t_after);
            // Saturates: billions of sub-steps times Newton iterations would wrap the protocol's uint32 (a review).
            reply.solver_iterations = static_cast<std::uint32_t>(std::min<std::uint64_t>(
                std::uint64_t{reply.solver_iterations} + static_cast<std::uint64_t>(r.iterations), UINT32_MAX));
            max_iterations = std::max(max_iterations, r.iterations);
            max_residual = std::max(max_residual, r.residual);
            progress.tick();
        }
    }

    reply.t = d.state().t;
    reply.dt_wanted = dt_wanted_;
    reply.substeps = static_cast<std::uint32_t>(n);
    reply.outputs["displacement"] = interface_->displacement(d.state().u);
    reply.outputs["velocity"] = interface_->velocity(d.state().u, d.state().v);
    const Energies e = per_metre_of_depth(d);
    double umax = 0;
    for (int i = 0; i < d.model().node_count(); ++i) umax = std::max(umax, d.state().u.segment<2>(3 * i).norm());
    reply.stats = Value(Value::Table{{"newton_iterations_max", Value(max_iterations)},
                                     {"newton_residual_max", Value(max_residual)},
                                     {"factorizations", Value(d.factorizations())},
                                     {"kinetic_energy", Value(e.kinetic)},
                                     {"strain_energy", Value(e.strain)},
                                     {"external_work", Value(e.external_work)},
                                     {"max_displacement", Value(umax)}});
    return reply;
}

// docs/protocol.md, ADVANCE: a structure always receives `force`, zeros when nothing acts on it.
std::optional<std::vector<std::string>> StructureSolver::advance_inputs() const { return std::vector<std::string>{"force"}; }

void StructureSolver::save() { saved_ = dyn().state(); }

void StructureSolver::restore() {
    if (!saved_) throw SolverError("bad_state", "structure: RESTORE without a SAVE");
    dyn().state() = *saved_;
}

Fields StructureSolver::snapshot() {
    const FrameDynamics& d = dyn();
    const Model& m = d.model();
    const auto n = static_cast<std::uint64_t>(m.node_count());
    F64Array nodes = F64Array::zeros(n, 2), disp = F64Array::zeros(n, 3), vel = F64Array::zeros(n, 3);
    for (std::uint64_t i = 0; i < n; ++i) {
        nodes(i, 0) = m.nodes[i].x();
        nodes(i, 1) = m.nodes[i].y();
        for (int k = 0; k < 3; ++k) {
            disp(i, k) = d.state().u[3 * i + k];
            vel(i, k) = d.state().v[3 * i + k];
        }
    }
    I32Array elements = I32Array::zeros(m.elements.size(), 2);
    for (std::size_t i = 0; i < m.elements.size(); ++i) {
        elements(i, 0) = m.elements[i].n1;
        elements(i, 1) = m.elements[i].n2;
    }
    const Energies e = per_metre_of_depth(d);
    Fields f;
    f["nodes"] = std::move(nodes);
    f["displacement"] = std::move(disp);
    f["velocity"] = std::move(vel);
    f["elements"] = std::move(elements);
    f["energy"] = F64Array({1, 3}, {e.kinetic, e.strain, e.external_work});
    return f;
}

std::vector<std::uint8_t> StructureSolver::checkpoint() { return encode_state(dyn().state(), dyn().model()); }

}  // namespace sphfsi::structure
