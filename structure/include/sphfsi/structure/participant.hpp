#pragma once
// The structure as a coupling participant: protocol::Solver on top of FrameDynamics and InterfaceMap.
#include <memory>
#include <optional>

#include "sphfsi/protocol/solver.hpp"
#include "sphfsi/structure/frame_dynamics.hpp"
#include "sphfsi/structure/interface.hpp"

namespace sphfsi::structure {

class StructureSolver : public protocol::Solver {
public:
    std::string kind() const override { return "structure"; }
    const schema::TableSchema& schema() const override;
    // Validates the section (bad_config on any problem), builds the model and, with a non-empty
    // `state`, resumes from that checkpoint. Publishes the interface when a member is wetted.
    protocol::InitReply init(const protocol::InitRequest& request) override;
    // Takes `substeps` equal steps (0: ceil(dt / dt_wanted)) under the scene loads plus the vertex
    // forces inputs["force"] (N per metre of depth, times section.depth) held constant over the window.
    protocol::AdvanceReply advance(const protocol::AdvanceRequest& request, protocol::Progress& progress) override;
    std::optional<std::vector<std::string>> advance_inputs() const override;  // {"force"}
    void save() override;
    void restore() override;
    protocol::Fields snapshot() override;
    std::vector<std::uint8_t> checkpoint() override;

    // min(time.dt_max, accuracy limit of the resolved modes).
    double dt_wanted() const { return dt_wanted_; }
    const FrameDynamics& dynamics() const { return *dynamics_; }
    const InterfaceMap& interface_map() const { return *interface_; }

private:
    FrameDynamics& dyn();
    std::unique_ptr<FrameDynamics> dynamics_;
    std::unique_ptr<InterfaceMap> interface_;
    std::optional<State> saved_;
    double dt_wanted_ = 0.0;
};

}  // namespace sphfsi::structure
