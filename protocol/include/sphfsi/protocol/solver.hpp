#pragma once
// What a participant program implements. The participant runtime (participant.hpp) owns the socket,
// the handshake, heartbeats and error replies; a Solver only does physics.
#include <atomic>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfsi/protocol/arrays.hpp"
#include "sphfsi/protocol/schema.hpp"
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::protocol {

// An error that travels as an ERROR reply: `code` is one of the codes of docs/protocol.md.
class CodedError : public std::runtime_error {
public:
    CodedError(std::string code, const std::string& message) : std::runtime_error(message), code_(std::move(code)) {}
    const std::string& code() const { return code_; }

private:
    std::string code_;
};

// An error a solver raises: a failure that ends the run (blow-up, non-convergence, bad configuration:
// "diverged", "not_converged", "bad_config", "internal") or a request it refuses ("bad_state",
// "bad_message": check_window below, RESTORE before SAVE).
class SolverError : public CodedError {
public:
    using CodedError::CodedError;
};

struct InitRequest {
    Value config;                          // the participant's scene section, validated, defaults filled
    double t0 = 0.0;                       // start time [s]
    std::optional<InterfaceMesh> interface;  // fluid: the structure's interface mesh when coupled
    std::vector<std::uint8_t> state;       // non-empty: resume from this checkpoint (from checkpoint())
    // Protocol 2, fluid: "displacement" and "velocity" (n, 2) of the interface at t0 when the structure starts
    // deformed or moving; empty = undeformed and at rest (always so under protocol 1).
    Fields interface_state;
};

struct InitReply {
    double dt_wanted = 0.0;                // largest step the solver wants next [s]
    std::optional<InterfaceMesh> interface;  // structure: the interface mesh it publishes
    Value info;                            // a table of facts for the record (particle count, ...)
    // Protocol 2, structure: "displacement" and "velocity" (n, 2) of its interface at t0; empty = undeformed
    // and at rest. Dropped (not sent) in a protocol-1 session.
    Fields interface_state;
};

struct AdvanceRequest {
    double t = 0.0;              // window start [s]; equals the solver's current time
    double dt = 0.0;             // window length [s]
    std::uint32_t substeps = 0;  // equal sub-steps to take; 0 = the solver chooses (adaptive)
    std::uint32_t iteration = 0; // implicit coupling iteration within this window (0 = first)
    Fields inputs;               // structure: "force"; fluid: "displacement", "velocity" (window end)
};

struct AdvanceReply {
    double t = 0.0;                       // time reached [s] (== request t + dt)
    double dt_wanted = 0.0;               // largest step the solver wants next [s]
    Fields outputs;                       // structure: "displacement", "velocity"; fluid: "force"
    std::uint32_t substeps = 0;           // sub-steps actually taken
    std::uint32_t solver_iterations = 0;  // e.g. Newton or PCISPH iterations summed over sub-steps
    Value stats;                          // a table of extra per-window numbers for the record
    double compute_s = 0.0;               // wall seconds inside Solver::advance (set by the runtime)
};

// The checks every solver applies to an ADVANCE before stepping (docs/protocol.md §3): `t` is finite and
// the window length `dt` a finite number > 0 (else `bad_message`, as for any field out of its range), and
// the window starts at the solver's current time `now` to 1e-9 x max(|now|, dt) (else `bad_state`): relative
// to the window's own length when it starts at t = 0. `who` names the solver in the message. One function,
// so that every participant reads the rule the same way.
void check_window(const AdvanceRequest& request, double now, const std::string& who);
// The time tolerance of that rule, also used by the coordinator to check the time an ADVANCED reports:
// `t` and `expected` are the same instant to 1e-9 x max(|expected|, dt).
bool same_instant(double t, double expected, double dt);
// A time with every digit and its unit ("0.10000000000000001 s"), for messages about these checks.
std::string seconds(double t);
// A sub-step count as ADVANCE carries it (a uint32), or nullopt when `count` is more than that holds (or not a
// number): a cast would wrap to a count of far larger steps, silently.
std::optional<std::uint32_t> substep_count(double count);
// The fewest equal sub-steps of at most `step` that cover `window` (at least 1; a step a hair short of
// window / n still gives n), as substep_count.
std::optional<std::uint32_t> substeps_to_cover(double window, double step);

// Progress counter the heartbeat thread reports; a solver bumps it once per sub-step.
struct Progress {
    std::atomic<std::uint64_t> steps{0};
    void tick() { steps.fetch_add(1, std::memory_order_relaxed); }
};

class Solver {
public:
    virtual ~Solver() = default;
    virtual std::string kind() const = 0;  // "fluid" or "structure"
    virtual const schema::TableSchema& schema() const = 0;
    virtual InitReply init(const InitRequest& request) = 0;
    virtual AdvanceReply advance(const AdvanceRequest& request, Progress& progress) = 0;
    // The names of the ADVANCE inputs this solver takes, as its last successful init() set it up: the
    // coordinator always sends exactly these (docs/protocol.md, ADVANCE), and the participant runtime refuses
    // a request with one missing or one more (bad_message) before advance() sees it. advance() itself
    // accepts what it is given (tests drive it without inputs). std::nullopt: no check.
    virtual std::optional<std::vector<std::string>> advance_inputs() const { return std::nullopt; }
    virtual void save() = 0;     // remember the current state (implicit coupling window start)
    virtual void restore() = 0;  // go back to the saved state
    virtual Fields snapshot() = 0;                   // fields for a record frame
    virtual std::vector<std::uint8_t> checkpoint() = 0;  // full state, opaque, for resume
};

}  // namespace sphfsi::protocol
