#include "sphfsi/structure/assembly.hpp"

#include <cmath>

namespace sphfsi::structure {
namespace {

std::array<int, 6> dofs(const Element& e) {
    return {3 * e.n1, 3 * e.n1 + 1, 3 * e.n1 + 2, 3 * e.n2, 3 * e.n2 + 1, 3 * e.n2 + 2};
}

// The element's six displacements out of the global vector u.
Vec6 element_dofs(const Element& e, const Vector& u) {
    const auto d = dofs(e);
    Vec6 de;
    for (int i = 0; i < 6; ++i) de[i] = u[d[i]];
    return de;
}

template <class ElementMatrix>
SparseMatrix assemble(const Model& model, ElementMatrix&& element_matrix) {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(36 * model.elements.size());
    for (const Element& e : model.elements) {
        const Mat6 k = element_matrix(e);
        const auto d = dofs(e);
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) t.emplace_back(d[i], d[j], k(i, j));
    }
    SparseMatrix K(model.dof_count(), model.dof_count());
    K.setFromTriplets(t.begin(), t.end());
    return K;
}

}  // namespace

SparseMatrix assemble_linear_stiffness(const Model& model) {
    return assemble(model, [](const Element& e) { return linear_stiffness(e); });
}

SparseMatrix assemble_mass(const Model& model, MassKind kind) {
    if (kind == MassKind::Lumped) return assemble(model, [](const Element& e) { return lumped_mass(e); });
    return assemble(model, [](const Element& e) { return consistent_mass(e); });
}

Vector corotational_internal_force(const Model& model, const Vector& u, SparseMatrix* tangent, double* strain_energy,
                                   SparseMatrix* material) {
    Vector f = Vector::Zero(model.dof_count());
    std::vector<Eigen::Triplet<double>> t, tm;
    if (tangent) t.reserve(36 * model.elements.size());
    if (material) tm.reserve(36 * model.elements.size());
    double energy = 0.0;
    Vec6 fe;
    Mat6 ke, kme;
    for (const Element& e : model.elements) {
        const auto d = dofs(e);
        const auto s = corotational_element(e, model.nodes[e.n1], model.nodes[e.n2], element_dofs(e, u), fe, tangent ? &ke : nullptr,
                                            material ? &kme : nullptr);
        energy += s.strain_energy;
        for (int i = 0; i < 6; ++i) f[d[i]] += fe[i];
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) {
                if (tangent) t.emplace_back(d[i], d[j], ke(i, j));
                if (material) tm.emplace_back(d[i], d[j], kme(i, j));
            }
    }
    if (tangent) {
        tangent->resize(model.dof_count(), model.dof_count());
        tangent->setFromTriplets(t.begin(), t.end());
    }
    if (material) {
        material->resize(model.dof_count(), model.dof_count());
        material->setFromTriplets(tm.begin(), tm.end());
    }
    if (strain_energy) *strain_energy = energy;
    return f;
}

std::vector<Eigen::Vector3d> corotational_deformations(const Model& model, const Vector& u) {
    std::vector<Eigen::Vector3d> out;
    out.reserve(model.elements.size());
    for (const Element& e : model.elements)
        out.push_back(corotational_deformation(e, model.nodes[e.n1], model.nodes[e.n2], element_dofs(e, u)));
    return out;
}

Vector corotational_deformation_damping(const Model& model, const Vector& u, const std::vector<Eigen::Vector3d>& at_start,
                                        double h, SparseMatrix* tangent) {
    Vector f = Vector::Zero(model.dof_count());
    std::vector<Eigen::Triplet<double>> t;
    if (tangent) t.reserve(36 * model.elements.size());
    Mat6 ke;
    for (std::size_t k = 0; k < model.elements.size(); ++k) {
        const Element& e = model.elements[k];
        const auto d = dofs(e);
        const Vec6 fe = corotational_deformation_damping(e, model.nodes[e.n1], model.nodes[e.n2], element_dofs(e, u),
                                                         at_start[k], h, tangent ? &ke : nullptr);
        for (int i = 0; i < 6; ++i) {
            f[d[i]] += fe[i];
            if (tangent)
                for (int j = 0; j < 6; ++j) t.emplace_back(d[i], d[j], ke(i, j));
        }
    }
    if (tangent) {
        tangent->resize(model.dof_count(), model.dof_count());
        tangent->setFromTriplets(t.begin(), t.end());
    }
    return f;
}

std::vector<double> element_angles(const Model& model, const Vector& u) {
    std::vector<double> out;
    out.reserve(model.elements.size());
    for (const Element& e : model.elements) {
        if (u.size() == 0) {
            out.push_back(e.beta0);
            continue;
        }
        const Vec2 x = model.nodes[e.n2] - model.nodes[e.n1] + u.segment<2>(3 * e.n2) - u.segment<2>(3 * e.n1);
        out.push_back(std::atan2(x.y(), x.x()));
    }
    return out;
}

}  // namespace sphfsi::structure
