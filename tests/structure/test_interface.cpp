// The interface mapping: mesh layout, rigid-link kinematics of the face vertices, and conservation
// of force and moment when vertex forces are lumped to the nodes.
#include <doctest/doctest.h>

#include <cmath>

#include "scenes.hpp"
#include "sphfsi/structure/interface.hpp"
#include "sphfsi/protocol/solver.hpp"
#include "sphfsi/structure/model.hpp"

using namespace structure_test;
using namespace sphfsi::structure;
using sphfsi::protocol::F64Array;

namespace {
// An inclined wetted member plus a dry one, 6 + 3 elements.
StructureConfig two_members() {
    Value s = beam(6);
    set(s, "members", Value(Value::Array{table({{"start", vec(0, 0)}, {"end", vec(0.6, 0.8)}, {"n_elements", Value(6)}}),
                                         table({{"start", vec(0.6, 0.8)}, {"end", vec(1.2, 0.8)}, {"n_elements", Value(3)},
                                                {"wetted", Value(false)}})}));
    return config(s);
}
// A deterministic, large, arbitrary displacement state (rotations up to ~3 rad).
Vector wild_state(const Model& m) {
    Vector u(m.dof_count());
    for (int i = 0; i < u.size(); ++i) u[i] = 0.3 * std::sin(1.7 * i + 0.3) + (i % 3 == 2 ? 2.5 * std::cos(0.9 * i) : 0.0);
    return u;
}
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
}  // namespace

TEST_SUITE("interface") {
TEST_CASE("mesh: two face vertices per node of wetted members, one CCW quad per element") {
    const auto cfg = two_members();
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const auto& mesh = map.mesh();
    CHECK(mesh.vertices.shape == std::vector<std::uint64_t>{14, 2});
    CHECK(mesh.cells.shape == std::vector<std::uint64_t>{6, 4});
    for (std::uint64_t c = 0; c < mesh.cells.rows(); ++c) {
        double area = 0;  // shoelace: positive for counter-clockwise
        for (int k = 0; k < 4; ++k) {
            const auto a = mesh.cells(c, k), b = mesh.cells(c, (k + 1) % 4);
            area += mesh.vertices(a, 0) * mesh.vertices(b, 1) - mesh.vertices(b, 0) * mesh.vertices(a, 1);
        }
        area *= 0.5;
        CHECK(area == doctest::Approx(t / 6.0).epsilon(1e-9));  // thickness x element length (1 m / 6)
    }
}

TEST_CASE("padding widens the published section on the requested side only") {
    Value s = beam(4);
    set(s, "members[0].interface_padding", vec(0.01, 0.03));  // left (+y for a member along +x), right (-y)
    const auto cfg = config(s);
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const auto& v = map.mesh().vertices;
    for (std::uint64_t i = 0; i < v.rows(); i += 2) {
        CHECK(v(i, 1) == doctest::Approx(-(t / 2 + 0.03)));     // bottom face, padded by 0.03
        CHECK(v(i + 1, 1) == doctest::Approx(t / 2 + 0.01));    // top face, padded by 0.01
    }
}

TEST_CASE("consistency: after any rotation the faces stay at t/2 from the node, normal to the rotated axis") {
    const auto cfg = two_members();
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const Vector u = wild_state(m);
    const F64Array d = map.displacement(u);
    for (std::size_t i = 0; i < map.vertex_count(); i += 2) {
        const int n = map.node_of(i);
        const Vec2 node = m.nodes[n] + u.segment<2>(3 * n);
        const Vec2 bottom = Vec2(map.mesh().vertices(i, 0) + d(i, 0), map.mesh().vertices(i, 1) + d(i, 1));
        const Vec2 top = Vec2(map.mesh().vertices(i + 1, 0) + d(i + 1, 0), map.mesh().vertices(i + 1, 1) + d(i + 1, 1));
        CHECK((bottom - node).norm() == doctest::Approx(t / 2).epsilon(1e-12));
        CHECK((top - node).norm() == doctest::Approx(t / 2).epsilon(1e-12));
        CHECK((top + bottom - 2 * node).norm() <= 1e-14);
        // The face normal turned by exactly theta from the reference normal (0.6, 0.8) -> (-0.8, 0.6).
        const Vec2 n0(-0.8, 0.6);
        const double th = u[3 * n + 2];
        const Vec2 want(std::cos(th) * n0.x() - std::sin(th) * n0.y(), std::sin(th) * n0.x() + std::cos(th) * n0.y());
        CHECK(((top - bottom) / t - want).norm() <= 1e-12);
    }
}

TEST_CASE("velocities are the time derivative of the vertex displacements") {
    const auto cfg = two_members();
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const Vector u = wild_state(m);
    Vector v(m.dof_count());
    for (int i = 0; i < v.size(); ++i) v[i] = std::cos(0.7 * i);
    const double eps = 1e-6;
    const F64Array dp = map.displacement(u + eps * v), dm = map.displacement(u - eps * v), vel = map.velocity(u, v);
    for (std::size_t k = 0; k < vel.values.size(); ++k)
        CHECK((dp.values[k] - dm.values[k]) / (2 * eps) == doctest::Approx(vel.values[k]).epsilon(1e-7).scale(1.0));
}

TEST_CASE("conservation: lumped nodal loads have the force and the moment (about any point) of the vertex forces") {
    const auto cfg = two_members();
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const Vector u = wild_state(m);
    const F64Array d = map.displacement(u);
    F64Array f = F64Array::zeros(map.vertex_count(), 2);
    for (std::size_t i = 0; i < f.values.size(); ++i) f.values[i] = 100.0 * std::sin(3.1 * i + 1.0);
    const double depth = 1.0;
    const Vector nodal = map.lump(f, u, depth);

    for (const Vec2& p : {Vec2(0, 0), Vec2(-3.0, 7.5), Vec2(12.0, -4.0)}) {
        Vec2 F_v = Vec2::Zero(), F_n = Vec2::Zero();
        double M_v = 0, M_n = 0, size = 0;
        for (std::size_t i = 0; i < map.vertex_count(); ++i) {
            const Vec2 x(map.mesh().vertices(i, 0) + d(i, 0), map.mesh().vertices(i, 1) + d(i, 1));
            const Vec2 fi(f(i, 0), f(i, 1));
            F_v += fi;
            M_v += cross(x - p, fi);
            size += (x - p).norm() * fi.norm();
        }
        for (int n = 0; n < m.node_count(); ++n) {
            const Vec2 x = m.nodes[n] + u.segment<2>(3 * n);
            const Vec2 fn = nodal.segment<2>(3 * n);
            F_n += fn;
            M_n += cross(x - p, fn) + nodal[3 * n + 2];
        }
        CHECK((F_v - F_n).norm() <= 1e-12 * f.values.size() * 100.0);
        MESSAGE("moment about (" << p.x() << ", " << p.y() << "): relative mismatch " << std::abs(M_v - M_n) / size);
        CHECK(std::abs(M_v - M_n) <= 1e-12 * size);
    }
}

TEST_CASE("lumping refuses wrong shapes and non-finite forces") {
    const auto cfg = two_members();
    const Model m = build_model(cfg);
    const InterfaceMap map(m, cfg);
    const Vector u = Vector::Zero(m.dof_count());
    try {
        map.lump(F64Array::zeros(3, 2), u, 1.0);
        FAIL("expected bad_message");
    } catch (const sphfsi::protocol::SolverError& e) {
        CHECK(e.code() == "bad_message");
    }
    F64Array f = F64Array::zeros(map.vertex_count(), 2);
    f(5, 1) = std::nan("");
    try {
        map.lump(f, u, 1.0);
        FAIL("expected bad_message");
    } catch (const sphfsi::protocol::SolverError& e) {
        CHECK(e.code() == "bad_message");  // an input refused, as docs/protocol.md's ADVANCE says
        CHECK(std::string(e.what()).find("vertex 5") != std::string::npos);
    }
}
}
