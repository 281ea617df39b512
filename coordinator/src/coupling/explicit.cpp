// Explicit (loosely coupled) schemes: one pass per window, no iterations.
#include "sphfsi/coordinator/coupling.hpp"

namespace sphfsi::coordinator {
using protocol::F64Array;
using protocol::Fields;

void predict(const std::string& kind, const InterfaceState& s, double dt, F64Array& d, F64Array& v) {
    d = s.displacement;
    v = s.velocity;
    if (kind == "none") return;
    if (kind == "linear" || s.previous_dt <= 0.0) {  // first-order: d + dt v
        for (std::size_t i = 0; i < d.values.size(); ++i) d.values[i] += dt * s.velocity.values[i];
        return;
    }
    // Second order: d_n + dt v_n + dt^2 / 2 a, which for equal windows is Piperno's (1997)
    // d_n + dt (3/2 v_n - 1/2 v_{n-1}). The acceleration comes from the last window's mean velocity
    // vbar = (d_n - d_{n-1}) / dt_prev, the velocity at that window's middle under a constant acceleration:
    // a = (v_n - vbar) / (dt_prev / 2). Exact for a constant acceleration whatever the two windows' lengths.
    // (Until 2026-11-27 vbar stood in for v_{n-1} in Piperno's form: a dt^2 / 4 off under a constant
    // acceleration, first order like the linear predictor.)
    // The velocity is predicted with the same acceleration, v_n + dt a, so that the pair is one the structure
    // can answer with: d - d_n = dt (v_n + v) / 2, Newmark's relation (generalized-alpha's to about 1e-3 dt^2 a
    // at rho_inf = 0.9; backward Euler's d - d_n = dt v it misses by dt^2 a / 2, as the old pairing did, and
    // the linear predictor's d_n + dt v_n with v_n meets). The fluid's solids then move as their velocities
    // say, and an implicit scheme's first iterate is consistent, which relaxation keeps (x + w r mixes it with
    // the structure's answers). Until 2026-11-27 the velocity
    // stayed v_n: a review found the displacement-only residual then dominated by that mismatch, and Aitken
    // diverging on a model problem.
    for (std::size_t i = 0; i < d.values.size(); ++i) {
        const double v_mean = (s.displacement.values[i] - s.previous_displacement.values[i]) / s.previous_dt;
        const double a = (s.velocity.values[i] - v_mean) / (0.5 * s.previous_dt);
        d.values[i] += dt * s.velocity.values[i] + 0.5 * dt * dt * a;
        v.values[i] += dt * a;
    }
}

namespace {
void accept_structure(InterfaceState& s, const StepResult& r, double dt) {
    const auto n = s.vertices();
    s.previous_displacement = s.displacement;
    s.previous_dt = dt;
    s.displacement = vertex_field("structure", r.reply.outputs, "displacement", n);
    s.velocity = vertex_field("structure", r.reply.outputs, "velocity", n);
}

Fields kinematics(const F64Array& d, const F64Array& v) { return Fields{{"displacement", d}, {"velocity", v}}; }

// Conventional serial staggered: fluid first on predicted kinematics, then the structure on the new forces.
class SerialExplicit : public CouplingScheme {
public:
    SerialExplicit(Session& s, std::string predictor) : session_(s), predictor_(std::move(predictor)) {}
    WindowOutcome run(const WindowPlan& p, InterfaceState& s) override {
        F64Array d, v;
        predict(predictor_, s, p.dt, d, v);
        WindowOutcome o;
        o.fluid = session_.advance("fluid", p.t, p.dt, p.fluid_substeps, 0, kinematics(d, v));
        s.force = vertex_field("fluid", o.fluid.reply.outputs, "force", s.vertices());
        s.fluid_displacement = d;
        o.structure = session_.advance("structure", p.t, p.dt, p.structure_substeps, 0, Fields{{"force", s.force}});
        o.structure_force = s.force;
        accept_structure(s, o.structure, p.dt);
        return o;
    }

private:
    Session& session_;
    std::string predictor_;
};

// Both sides advance at once on the other's window-start data: the structure on the last forces,
// the fluid on predicted kinematics. Half the latency of the serial scheme, one step more lag.
class ParallelExplicit : public CouplingScheme {
public:
    ParallelExplicit(Session& s, std::string predictor) : session_(s), predictor_(std::move(predictor)) {}
    WindowOutcome run(const WindowPlan& p, InterfaceState& s) override {
        F64Array d, v;
        predict(predictor_, s, p.dt, d, v);
        auto fseq = session_.start_advance("fluid", p.t, p.dt, p.fluid_substeps, 0, kinematics(d, v));
        auto sseq = session_.start_advance("structure", p.t, p.dt, p.structure_substeps, 0, Fields{{"force", s.force}});
        WindowOutcome o;
        o.concurrent = true;
        o.fluid = session_.finish_advance("fluid", fseq);
        o.structure = session_.finish_advance("structure", sseq);
        o.structure_force = s.force;  // the window-start force it was sent
        s.force = vertex_field("fluid", o.fluid.reply.outputs, "force", s.vertices());
        s.fluid_displacement = d;
        accept_structure(s, o.structure, p.dt);
        return o;
    }

private:
    Session& session_;
    std::string predictor_;
};
}  // namespace

std::unique_ptr<CouplingScheme> make_implicit_scheme(const Value& coupling, Session& session, Log log);

std::unique_ptr<CouplingScheme> make_scheme(const Value& c, Session& session, Log log) {
    const std::string& scheme = c.at("scheme").as_string();
    const std::string& predictor = c.at("predictor").as_string();
    if (scheme == "serial-explicit") return std::make_unique<SerialExplicit>(session, predictor);
    if (scheme == "parallel-explicit") return std::make_unique<ParallelExplicit>(session, predictor);
    return make_implicit_scheme(c, session, std::move(log));
}

}  // namespace sphfsi::coordinator
