#pragma once
// Driving the fluid solver through its participant interface, as the coordinator would.
#include <cmath>
#include <functional>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "sphfsi/fluid/sph_solver.hpp"

namespace fluid_test {

inline std::unique_ptr<sphfsi::fluid::SphSolver> start(const sphfsi::Value& config, double t0 = 0.0) {
    auto solver = std::make_unique<sphfsi::fluid::SphSolver>();
    sphfsi::protocol::InitRequest req;
    req.config = config;
    req.t0 = t0;
    solver->init(req);
    return solver;
}

// A fluid around an interface mesh, as INIT starts it: with the structure's start state, or resumed from a
// checkpoint.
inline std::unique_ptr<sphfsi::fluid::SphSolver> start_around(const sphfsi::Value& config,
                                                             const sphfsi::protocol::InterfaceMesh& mesh,
                                                             sphfsi::protocol::Fields interface_state = {},
                                                             std::vector<std::uint8_t> state = {}) {
    auto solver = std::make_unique<sphfsi::fluid::SphSolver>();
    sphfsi::protocol::InitRequest req;
    req.config = config;
    req.interface = mesh;
    req.interface_state = std::move(interface_state);
    req.state = std::move(state);
    solver->init(req);
    return solver;
}

// The most fluid particles beyond a wall surface after any one step of a window (its "wall_crossings"
// statistic): the validation scenes' "no particle crosses a wall" is checked at every step, not only at the
// windows' ends.
inline std::size_t wall_crossings(const sphfsi::protocol::AdvanceReply& reply) {
    return static_cast<std::size_t>(reply.stats.at("wall_crossings").as_int());
}

// Advances in windows of `window` seconds (adaptive sub-steps) up to t_end, calling `each` after every
// window with the reply.
inline void run(sphfsi::fluid::SphSolver& solver, double t_end, double window,
                const std::function<void(const sphfsi::protocol::AdvanceReply&)>& each = {}) {
    sphfsi::protocol::Progress progress;
    while (solver.simulation().time() < t_end - 1e-12) {
        sphfsi::protocol::AdvanceRequest req;
        req.t = solver.simulation().time();
        req.dt = std::min(window, t_end - req.t);
        const auto reply = solver.advance(req, progress);
        if (each) each(reply);
    }
}

}  // namespace fluid_test
