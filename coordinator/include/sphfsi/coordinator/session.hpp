#pragma once
// The participants as the coupling schemes see them: ADVANCE / SAVE / RESTORE with timing, and the
// interface state passed between them.
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "sphfsi/coordinator/hub.hpp"
#include "sphfsi/protocol/arrays.hpp"

namespace sphfsi::coordinator {

struct StepResult {
    protocol::AdvanceReply reply;
    double roundtrip_s = 0.0;  // wall time from sending ADVANCE to having the reply decoded
};

class Session {
public:
    explicit Session(Hub& hub) : hub_(hub) {}
    std::uint64_t start_advance(const std::string& role, double t, double dt, std::uint32_t substeps,
                                std::uint32_t iteration, protocol::Fields inputs);
    StepResult finish_advance(const std::string& role, std::uint64_t seq);
    StepResult advance(const std::string& role, double t, double dt, std::uint32_t substeps, std::uint32_t iteration,
                       protocol::Fields inputs) {
        return finish_advance(role, start_advance(role, t, dt, substeps, iteration, std::move(inputs)));
    }
    void save(const std::string& role);
    void restore(const std::string& role);
    Hub& hub() { return hub_; }

private:
    struct Asked {  // the ADVANCE in flight, to check its reply against
        double t = 0.0, dt = 0.0;
        std::uint32_t substeps = 0;
    };
    Hub& hub_;
    std::map<std::string, Asked> asked_;
};

// IQN-ILS's secant pairs of one converged window, newest first: V the differences of the displacement
// residuals (2 values per vertex), W those of the structure's answers, velocities included (4 per vertex).
struct SecantWindow {
    std::vector<std::vector<double>> V, W;
};
// Those of the last coupling.iqn_reuse windows that left pairs, newest first.
using SecantHistory = std::deque<SecantWindow>;

// What travels between the two sides, as of the start of the current window.
struct InterfaceState {
    protocol::InterfaceMesh mesh;
    protocol::F64Array displacement, velocity;  // structure's latest (n, 2)
    protocol::F64Array previous_displacement;   // one window earlier, for the quadratic predictor
    protocol::F64Array force;                   // fluid's latest (n, 2)
    // Where the fluid last moved the interface to (the predicted or iterated window-end displacement it was
    // given): the other side of the interface energy balance (docs/coupling.md).
    protocol::F64Array fluid_displacement;
    // The balance since t0: work done on the structure and energy created at the interface [J/m], the
    // yardstick for the energy checks: the fluid's mechanical energy after the first window (0: not known
    // yet), and the fluid's plus the structure's less the structure's own load work after the first window
    // (NaN: not known yet; it may be 0 or negative, which must not read as unknown: the gain check would
    // then re-take its baseline every window and never run, a review). energy_guard.hpp uses them.
    double work_total = 0.0, created_total = 0.0, fluid_energy = 0.0;
    double total_energy = std::numeric_limits<double>::quiet_NaN();
    double previous_dt = 0.0;
    // Said once that the gain check is off for a structure that reports its energies but not its external
    // work (not checkpointed: a resumed run says it once more).
    bool no_external_work_said = false;
    // Kept across windows by IQN-ILS (accelerators.hpp), here so that a checkpoint holds it and a resumed
    // run iterates as the uninterrupted one (until 2026-11-27 it did not, a review).
    SecantHistory secants;

    void reset(const protocol::InterfaceMesh& m);
    std::size_t vertices() const { return mesh.vertices.rows(); }
};

// Reads a named (n, 2) f8 output, or fails naming the participant and the field.
const protocol::F64Array& vertex_field(const std::string& role, const protocol::Fields& fields, const std::string& name,
                                       std::size_t vertices);

}  // namespace sphfsi::coordinator
