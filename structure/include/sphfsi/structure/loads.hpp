#pragma once
// The scene's own prescribed loads (point, distributed, self-weight) as a nodal load vector.
#include <vector>

#include "sphfsi/structure/config.hpp"
#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

class SceneLoads {
public:
    SceneLoads(const StructureConfig& config, const Model& model);

    // Nodal loads at time t. Distributed loads (and gravity) are dead loads per unit reference
    // length; their fixed-end moments use the element orientation of `u` (the configuration at the
    // start of the step) when `follow_rotation`, else the reference orientation.
    // `side`: at a switch time (History), the value a step ending there sees (Left) or one starting there.
    Vector at(double t, const Vector& u, bool follow_rotation, History::Side side = History::Side::Right) const;
    // The loads' mean over [t0, t1] (History::mean_factor), for a step that a switch falls inside.
    Vector mean(double t0, double t1, const Vector& u, bool follow_rotation) const;
    // Every time a load switches on or off, sorted: adaptive stepping lands on them (StructureSolver::advance).
    std::vector<double> switch_times() const;

    bool empty() const { return point_.empty() && distributed_.empty(); }

private:
    // The nodal loads, each load's spec scaled by factor(its history).
    template <class Factor>
    Vector assemble(const Factor& factor, const Vector& u, bool follow_rotation) const;

    struct NodalLoad {
        int node;
        Vec2 force;
        double moment;
        History history;
    };
    struct MemberLoad {
        int member;
        Vec2 q;
        History history;
    };
    const Model* model_;
    std::vector<NodalLoad> point_;
    std::vector<MemberLoad> distributed_;
};

// Nodal load vector of point loads held constant (used for the preload of a plucked start).
Vector point_load_vector(const Model& model, const std::vector<PointLoadSpec>& loads, const char* what);

}  // namespace sphfsi::structure
