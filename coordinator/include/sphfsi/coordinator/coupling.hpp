#pragma once
// Coupling schemes and the window schedule (docs/coupling.md). A scheme advances both participants
// over one window and leaves the interface state at the window's end.
#include <functional>
#include <memory>
#include <string>

#include "sphfsi/coordinator/session.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::coordinator {

// Why a window has the length it has; recorded per window as an integer column with this legend.
enum class WindowRule : int { Thesis = 0, MultiRate = 1, Fixed = 2, FluidAlone = 3, StructureAlone = 4 };
const char* window_rule_legend();

struct WindowPlan {
    double t = 0.0, dt = 0.0;
    std::uint32_t fluid_substeps = 0, structure_substeps = 0;  // 0 = participant chooses (adaptive)
    WindowRule rule = WindowRule::Thesis;
    bool clipped = false;  // shortened to land on an output time or the end
    double wanted = 0.0;   // the window its rule wanted, before landing on a stop
};

// Shortens p.dt (from p.t) so that the windows land exactly on t_stop without a sliver of a window before
// it; sets p.clipped when the window is shorter than wanted.
void land_on_stop(WindowPlan& p, double t_stop);

// Chooses the next window from the steps both sides want (coupled runs).
class Schedule {
public:
    explicit Schedule(const Value& coupling);
    WindowPlan next(double t, double fluid_dt, double structure_dt, double t_stop) const;
    bool one_structure_step() const { return one_structure_step_; }

private:
    std::string rule_;
    double fixed_dt_ = 0.0;
    int max_fluid_steps_ = 1;
    bool one_structure_step_ = false;  // coupling.structure_steps = "window"
};

struct WindowOutcome {
    StepResult fluid, structure;
    // The interface force the structure was advanced with: the fluid's force of this window, or for
    // parallel-explicit of the last one (the interface energy balance needs it).
    protocol::F64Array structure_force;
    std::uint32_t iterations = 1;  // coupling iterations (1 for explicit schemes)
    bool concurrent = false;       // both sides advanced at once (parallel-explicit): their waits overlap
    double residual = 0.0;         // final interface displacement residual norm [m] (0 for explicit)
    bool converged = true;
    // Set when the window must end the run (coupling.on_max_iterations = "error"): the loop records the
    // window first, so the record keeps the residual and iteration count that ended it.
    std::string stop_run;
};

using Log = std::function<void(const std::string&)>;

class CouplingScheme {
public:
    virtual ~CouplingScheme() = default;
    virtual WindowOutcome run(const WindowPlan& plan, InterfaceState& state) = 0;
};

std::unique_ptr<CouplingScheme> make_scheme(const Value& coupling, Session& session, Log log);

// Interface kinematics predicted at the window end from the state at its start.
void predict(const std::string& kind, const InterfaceState& s, double dt, protocol::F64Array& d, protocol::F64Array& v);

}  // namespace sphfsi::coordinator
