#pragma once
// The participant adapter: sphfsi::protocol::Solver over Simulation2D. Translates INIT/ADVANCE/... into
// simulation calls, drives the solid particles from the structure's interface mesh and maps the fluid's
// forces back onto its vertices.
#include <memory>
#include <optional>

#include "sphfsi/fluid/settings.hpp"
#include "sphfsi/fluid/simulation.hpp"
#include "sphfsi/fluid/solid_coupling.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {

class SphSolver : public protocol::Solver {
public:
    std::string kind() const override { return "fluid"; }
    const schema::TableSchema& schema() const override;
    protocol::InitReply init(const protocol::InitRequest& request) override;
    protocol::AdvanceReply advance(const protocol::AdvanceRequest& request, protocol::Progress& progress) override;
    std::optional<std::vector<std::string>> advance_inputs() const override;  // coupled: displacement, velocity
    void save() override;
    void restore() override;
    protocol::Fields snapshot() override;
    std::vector<std::uint8_t> checkpoint() override;

    // For tests and the benchmark.
    Simulation2D& simulation() { return *sim_; }
    const InterfaceCoupling* coupling() const { return coupling_ ? &*coupling_ : nullptr; }

private:
    void require_init() const;
    double next_step_wanted();
    FluidSettings settings_;
    std::unique_ptr<Simulation2D> sim_;
    std::optional<InterfaceCoupling> coupling_;
    InterfaceCoupling::State saved_coupling_;
    // The interface displacement (n x 2, row-major) the run started from; empty: undeformed. Checkpointed, so
    // a resume clears the water around the structure where the first start did.
    std::vector<double> start_displacement_;
    bool state_has_correction_ = true;  // the checkpoint being read is SPHFSIP3, which holds the correction L
    // A step below the floor found at a window's end, raised by the next ADVANCE (next_step_wanted).
    std::optional<protocol::SolverError> step_floor_failure_;
};

}  // namespace sphfsi::fluid
