#include "sphfsi/structure/model.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {

using protocol::SolverError;

int Model::node_at(const Point2& p) const {
    // Same rule as the schema's cross-key checks: 1e-6 of the largest member.
    const double tol = 1e-6 * characteristic_length;
    for (int i = 0; i < node_count(); ++i)
        if ((nodes[i] - Vec2(p[0], p[1])).norm() <= tol) return i;
    return -1;
}

Model build_model(const StructureConfig& config) {
    Model model;
    double size = 0;
    for (const auto& m : config.members) size = std::max(size, std::hypot(m.end[0] - m.start[0], m.end[1] - m.start[1]));
    if (!(size > 0)) throw SolverError("bad_config", "structure.members: no member with a length > 0");
    model.characteristic_length = size;

    const auto& mat = config.material;
    const auto& sec = config.section;
    // A plate strip in cylindrical bending cannot contract sideways: effective modulus E / (1 - nu^2).
    const double E = sec.plane_strain ? mat.E / (1.0 - mat.nu * mat.nu) : mat.E;
    const double A = sec.depth * sec.thickness;
    const double I = sec.depth * sec.thickness * sec.thickness * sec.thickness / 12.0;

    // Where members meet: a node at any member's end point (this member's or another's, listed before or after)
    // joins the node already there, so the order of `members` does not matter. Interior nodes of members that
    // merely cross, where no member ends, stay apart: the schema joins members at their ends.
    std::vector<Vec2> member_ends;
    for (const auto& m : config.members) {
        member_ends.emplace_back(m.start[0], m.start[1]);
        member_ends.emplace_back(m.end[0], m.end[1]);
    }
    const double joint_tol = 1e-6 * size;  // node_at's tolerance
    auto at_a_member_end = [&](const Vec2& p) {
        return std::any_of(member_ends.begin(), member_ends.end(), [&](const Vec2& e) { return (e - p).norm() <= joint_tol; });
    };
    std::set<std::pair<int, int>> element_keys;
    for (std::size_t mi = 0; mi < config.members.size(); ++mi) {
        const auto& ms = config.members[mi];
        const std::string where = "structure.members[" + std::to_string(mi) + "]";
        if (ms.n_elements < 1) throw SolverError("bad_config", where + ".n_elements must be >= 1");
        Vec2 a(ms.start[0], ms.start[1]), b(ms.end[0], ms.end[1]);
        std::vector<int> ids;
        for (int k = 0; k <= ms.n_elements; ++k) {
            Vec2 p = a + (static_cast<double>(k) / ms.n_elements) * (b - a);
            const bool joint = k == 0 || k == ms.n_elements || at_a_member_end(p);
            int id = joint ? model.node_at({p.x(), p.y()}) : -1;
            if (id < 0) {
                id = model.node_count();
                model.nodes.push_back(p);
            }
            ids.push_back(id);
        }
        std::vector<int> elems;
        for (int k = 0; k < ms.n_elements; ++k) {
            Element e;
            e.n1 = ids[k];
            e.n2 = ids[k + 1];
            e.member = static_cast<int>(mi);
            Vec2 d = model.nodes[e.n2] - model.nodes[e.n1];
            e.L0 = d.norm();
            e.beta0 = std::atan2(d.y(), d.x());
            if (!(e.L0 > 1e-9 * size))
                throw SolverError("bad_config", where + ".n_elements = " + std::to_string(ms.n_elements) +
                                                    " gives elements of length " + std::to_string(e.L0) + " m");
            if (!element_keys.insert({std::min(e.n1, e.n2), std::max(e.n1, e.n2)}).second)
                throw SolverError("bad_config", where + " overlaps another member (an element is defined twice)");
            e.EA = E * A;
            e.EI = E * I;
            e.rhoA = mat.rho * A;
            elems.push_back(static_cast<int>(model.elements.size()));
            model.elements.push_back(e);
        }
        model.member_nodes.push_back(std::move(ids));
        model.member_elements.push_back(std::move(elems));
    }

    // Constraint basis T: for each node, the admissible directions of its three DOFs.
    const int n = model.node_count();
    std::vector<const SupportSpec*> support(n, nullptr);
    for (std::size_t i = 0; i < config.supports.size(); ++i) {
        int id = model.node_at(config.supports[i].at);
        if (id < 0)
            throw SolverError("bad_config", "structure.supports[" + std::to_string(i) + "].at is not a node");
        support[id] = &config.supports[i];
    }
    std::vector<Eigen::Triplet<double>> t;
    int col = 0;
    for (int i = 0; i < n; ++i) {
        const SupportType type = support[i] ? support[i]->type : SupportType::Free;
        switch (type) {
            case SupportType::Clamped: break;
            case SupportType::Pinned: t.emplace_back(3 * i + 2, col++, 1.0); break;
            case SupportType::Roller: {
                Vec2 nrm(support[i]->normal[0], support[i]->normal[1]);
                nrm.stableNormalize();  // normalize() leaves [1e-200, 0] as it is: its squared norm underflows
                // Free to move along the surface tangent (ny, -nx) only.
                if (nrm.y() != 0.0) t.emplace_back(3 * i, col, nrm.y());
                if (nrm.x() != 0.0) t.emplace_back(3 * i + 1, col, -nrm.x());
                ++col;
                t.emplace_back(3 * i + 2, col++, 1.0);
                break;
            }
            case SupportType::Free:
                for (int k = 0; k < 3; ++k) t.emplace_back(3 * i + k, col++, 1.0);
                break;
        }
    }
    if (col == 0) throw SolverError("bad_config", "structure.supports: every degree of freedom is fixed");
    model.T.resize(3 * n, col);
    model.T.setFromTriplets(t.begin(), t.end());
    return model;
}

}  // namespace sphfsi::structure
