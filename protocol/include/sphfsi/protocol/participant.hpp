#pragma once
// The participant runtime: everything a participant program does besides physics. It parses the
// command line (--connect ENDPOINT --token TOKEN --name NAME), connects a DEALER socket to the
// coordinator, performs HELLO/WELCOME, sends heartbeats from a background thread, dispatches INIT /
// ADVANCE / SAVE / RESTORE / SNAPSHOT / CHECKPOINT / BYE to the Solver, and turns exceptions into ERROR
// replies. See docs/protocol.md.
#include <memory>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::protocol {

// Runs until BYE, a fatal error or the coordinator going silent; returns the process exit code.
int run_participant(int argc, char** argv, std::unique_ptr<Solver> solver);

}  // namespace sphfsi::protocol
