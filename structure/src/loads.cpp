#include "sphfsi/structure/loads.hpp"

#include <algorithm>

#include "sphfsi/protocol/solver.hpp"
#include "sphfsi/structure/assembly.hpp"

namespace sphfsi::structure {

using protocol::SolverError;

namespace {
int require_node(const Model& model, const Point2& at, const std::string& where) {
    int id = model.node_at(at);
    if (id < 0) throw SolverError("bad_config", where + ".at is not a node of any member");
    return id;
}
}  // namespace

SceneLoads::SceneLoads(const StructureConfig& config, const Model& model) : model_(&model) {
    for (std::size_t i = 0; i < config.point_loads.size(); ++i) {
        const auto& p = config.point_loads[i];
        int id = require_node(model, p.at, "structure.point_loads[" + std::to_string(i) + "]");
        point_.push_back({id, Vec2(p.force[0], p.force[1]), p.moment, p.history});
    }
    for (std::size_t i = 0; i < config.distributed_loads.size(); ++i) {
        const auto& d = config.distributed_loads[i];
        if (d.member < 0 || d.member >= static_cast<int>(model.member_elements.size()))
            throw SolverError("bad_config", "structure.distributed_loads[" + std::to_string(i) + "].member = " +
                                                std::to_string(d.member) + " names no member");
        distributed_.push_back({d.member, Vec2(d.q[0], d.q[1]), d.history});
    }
    if (config.gravity) {
        // Self-weight: q = rho A g on every member, always on.
        const Vec2 g(config.gravity_vector[0], config.gravity_vector[1]);
        for (std::size_t m = 0; m < model.member_elements.size(); ++m) {
            if (model.member_elements[m].empty()) continue;
            const double rhoA = model.elements[model.member_elements[m].front()].rhoA;
            distributed_.push_back({static_cast<int>(m), rhoA * g, History{}});
        }
    }
}

std::vector<double> SceneLoads::switch_times() const {
    std::vector<double> times;
    auto add = [&](const History& h) {
        times.push_back(h.start_time);
        if (h.end_time) times.push_back(*h.end_time);
    };
    for (const auto& p : point_) add(p.history);
    for (const auto& d : distributed_) add(d.history);
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end()), times.end());
    return times;
}

template <class Factor>
Vector SceneLoads::assemble(const Factor& factor, const Vector& u, bool follow_rotation) const {
    const Model& model = *model_;
    Vector f = Vector::Zero(model.dof_count());
    for (const auto& p : point_) {
        const double s = factor(p.history);
        if (s == 0.0) continue;
        f.segment<2>(3 * p.node) += s * p.force;
        f[3 * p.node + 2] += s * p.moment;
    }
    if (distributed_.empty()) return f;
    const auto angles = element_angles(model, follow_rotation ? u : Vector());
    for (const auto& d : distributed_) {
        const double s = factor(d.history);
        if (s == 0.0) continue;
        for (int ei : model.member_elements[d.member]) {
            const Element& e = model.elements[ei];
            const Vec6 fe = uniform_load(e, s * d.q, angles[ei]);
            f.segment<3>(3 * e.n1) += fe.head<3>();
            f.segment<3>(3 * e.n2) += fe.tail<3>();
        }
    }
    return f;
}

Vector SceneLoads::at(double t, const Vector& u, bool follow_rotation, History::Side side) const {
    return assemble([&](const History& h) { return h.factor(t, side); }, u, follow_rotation);
}

Vector SceneLoads::mean(double t0, double t1, const Vector& u, bool follow_rotation) const {
    return assemble([&](const History& h) { return h.mean_factor(t0, t1); }, u, follow_rotation);
}

Vector point_load_vector(const Model& model, const std::vector<PointLoadSpec>& loads, const char* what) {
    Vector f = Vector::Zero(model.dof_count());
    for (std::size_t i = 0; i < loads.size(); ++i) {
        int id = require_node(model, loads[i].at, std::string(what) + "[" + std::to_string(i) + "]");
        f[3 * id] += loads[i].force[0];
        f[3 * id + 1] += loads[i].force[1];
        f[3 * id + 2] += loads[i].moment;
    }
    return f;
}

}  // namespace sphfsi::structure
