#include <cmath>

#include "sphfsi/coordinator/coupling.hpp"

namespace sphfsi::coordinator {

const char* window_rule_legend() {
    return "0 = thesis (one fluid step; structure n = int(dt_f/dt_s)+1), 1 = multi-rate (several fluid steps), "
           "2 = fixed (coupling.window_dt), 3 = fluid alone (to the next output), 4 = structure alone (to the next "
           "output; its wanted step under a ramp or sine load, at most 1/(20 f) under a sine); "
           "with coupling.structure_steps = \"window\" the structure takes one step per coupled window";
}

Schedule::Schedule(const Value& c)
    : rule_(c.at("window").as_string()), fixed_dt_(c.number_or("window_dt", 0.0)),
      max_fluid_steps_(static_cast<int>(c.at("max_fluid_steps").as_int())),
      one_structure_step_(c.at("structure_steps").as_string() == "window") {}

void land_on_stop(WindowPlan& p, double t_stop) {
    // Take what is left when it is one window to within 1e-6 of it; split it into two equal windows when one
    // window would leave less than a quarter of a window after it. That sliver had been a window of its own,
    // down to 1e-11 s: the fluid's force over it was 25 times the force around it, and the quadratic
    // predictor, which divides by the last window's length, then created energy at the interface (a review,
    // 2026-11-27). Neither ever makes a window longer than wanted by more than 1e-6 of it.
    const double wanted = p.dt, left = t_stop - p.t;
    p.wanted = wanted;
    if (wanted >= left * (1 - 1e-6))
        p.dt = left;
    else if (left - wanted < 0.25 * wanted)
        p.dt = 0.5 * left;
    p.clipped = p.dt < wanted * (1 - 1e-12);
}

WindowPlan Schedule::next(double t, double fluid_dt, double structure_dt, double t_stop) const {
    WindowPlan p;
    p.t = t;
    if (rule_ == "thesis") {
        // The thesis couples every fluid step and sub-cycles the beam n = int(dt_SPH / dt_FEM,max) + 1 times.
        p.rule = WindowRule::Thesis;
        p.dt = fluid_dt;
        p.fluid_substeps = 1;
    } else if (rule_ == "multi-rate") {
        p.rule = WindowRule::MultiRate;
        p.dt = max_fluid_steps_ * fluid_dt;
        p.fluid_substeps = 0;  // the fluid keeps its own CFL step inside the window
    } else {
        p.rule = WindowRule::Fixed;
        p.dt = fixed_dt_;
        p.fluid_substeps = 0;
    }
    land_on_stop(p, t_stop);
    std::optional<std::uint32_t> count = 1;  // why one: docs/coupling.md, "A light structure: one structure step per window"
    if (!one_structure_step_)
        count = p.rule == WindowRule::Thesis ? protocol::substep_count(std::floor(p.dt / structure_dt) + 1)
                                             : protocol::substeps_to_cover(p.dt, structure_dt);
    if (!count)
        throw ParticipantFailure("structure", "garbage", "wants a step of " + protocol::seconds(structure_dt) +
                                                             ", too small to cover a window of " + protocol::seconds(p.dt) +
                                                             " in the sub-steps an ADVANCE can ask for");
    p.structure_substeps = *count;
    return p;
}

}  // namespace sphfsi::coordinator
