#include "sphfsi/structure/checkpoint.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::structure {

static_assert(std::endian::native == std::endian::little, "checkpoint layout assumes a little-endian host");

namespace {

constexpr std::string_view magic = "sphfsi-structure-state-v3";
// Version 1 (before 2026-11-27) had no energy check state, version 2 (the same day) its scale alone; both are
// read, and the resumed run goes without the energy check (State::initial_energy = NaN).
constexpr std::string_view magic_v1 = "sphfsi-structure-state-v1", magic_v2 = "sphfsi-structure-state-v2";

// Changes whenever nodes or connectivity change, so a checkpoint cannot resume a different mesh.
double fingerprint(const Model& model) {
    double f = 0;
    for (std::size_t i = 0; i < model.nodes.size(); ++i)
        f += (i + 1.0) * model.nodes[i].x() + 0.5 * (i + 2.0) * model.nodes[i].y();
    for (std::size_t i = 0; i < model.elements.size(); ++i)
        f += 1e-3 * (i + 1.0) * (model.elements[i].n1 + 2.0 * model.elements[i].n2);
    return f;
}

struct Writer {
    std::vector<std::uint8_t> out;
    void raw(const void* p, std::size_t n) {
        const auto* b = static_cast<const std::uint8_t*>(p);
        out.insert(out.end(), b, b + n);
    }
    template <class T>
    void put(T x) { raw(&x, sizeof x); }
};

struct Reader {
    const std::vector<std::uint8_t>& in;
    std::size_t at = 0;
    void raw(void* p, std::size_t n) {
        if (at + n > in.size()) throw protocol::SolverError("bad_config", "structure: checkpoint is truncated");
        std::memcpy(p, in.data() + at, n);
        at += n;
    }
    template <class T>
    T get() {
        T x;
        raw(&x, sizeof x);
        return x;
    }
};

}  // namespace

std::vector<std::uint8_t> encode_state(const State& s, const Model& model) {
    Writer w;
    w.raw(magic.data(), magic.size());
    w.put<std::uint64_t>(static_cast<std::uint64_t>(model.dof_count()));
    w.put<std::uint64_t>(model.elements.size());
    w.put<double>(fingerprint(model));
    w.put<double>(s.t);
    w.put<std::uint64_t>(s.step);
    w.put<double>(s.external_work);
    w.put<double>(s.initial_energy);
    w.put<double>(s.energy_scale);
    for (const Vector* x : {&s.u, &s.v, &s.a}) w.raw(x->data(), sizeof(double) * x->size());
    return w.out;
}

State decode_state(const std::vector<std::uint8_t>& bytes, const Model& model) {
    Reader r{bytes};
    std::string head(magic.size(), '\0');
    r.raw(head.data(), head.size());
    static_assert(magic.size() == magic_v1.size() && magic.size() == magic_v2.size());
    const bool v1 = head == magic_v1, v2 = head == magic_v2;
    if (head != magic && !v1 && !v2) throw protocol::SolverError("bad_config", "structure: the resume state is not a structure checkpoint");
    const auto dofs = r.get<std::uint64_t>(), elements = r.get<std::uint64_t>();
    const double print = r.get<double>();
    auto other_mesh = [](const std::string& what) {
        return protocol::SolverError("bad_config", "structure: the checkpoint belongs to a different mesh (" + what + ")");
    };
    if (elements != model.elements.size())
        throw other_mesh(std::to_string(elements) + " elements; this scene has " + std::to_string(model.elements.size()));
    if (dofs != static_cast<std::uint64_t>(model.dof_count()))
        throw other_mesh(std::to_string(dofs) + " degrees of freedom; this scene has " + std::to_string(model.dof_count()));
    if (print != fingerprint(model)) throw other_mesh("other node positions or connections, by its fingerprint");
    State s;
    s.t = r.get<double>();
    s.step = r.get<std::uint64_t>();
    s.external_work = r.get<double>();
    s.initial_energy = v1 || v2 ? std::numeric_limits<double>::quiet_NaN() : r.get<double>();
    s.energy_scale = v1 ? 0.0 : r.get<double>();
    for (Vector* x : {&s.u, &s.v, &s.a}) {
        x->resize(model.dof_count());
        r.raw(x->data(), sizeof(double) * x->size());
    }
    if (r.at != bytes.size()) throw protocol::SolverError("bad_config", "structure: checkpoint has trailing bytes");
    // A damaged file: NaN in the state went out in READY's interface state, and t = inf passed every time check.
    const bool initial_ok = v1 || v2 || (s.initial_energy >= 0.0 && std::isfinite(s.initial_energy));
    if (!std::isfinite(s.t) || !std::isfinite(s.external_work) || !initial_ok ||
        !(s.energy_scale >= 0.0 && std::isfinite(s.energy_scale)) ||
        !s.u.allFinite() || !s.v.allFinite() || !s.a.allFinite())
        throw protocol::SolverError("bad_config", "structure: the checkpoint holds a time, load work, energy baseline or scale, "
                                                  "displacement, velocity or acceleration that is not a finite number "
                                                  "(or a negative energy); the file is damaged");
    // A state no run holds: a clamped node that moved (accepted, such a file had a clamped node 0.5 m away,
    // and the run stopped at its second step for creating energy; a review, 2026-11-27). A DOF the supports
    // fix outright (T's row is zero) holds exactly 0 in every run: u = T q there, and v and a are made from
    // changes of u. A roller on a slanted surface is only checked in u, to round-off: its v and a carry
    // c0 = 1/(beta h^2) times u's round-off off the surface (8e-3 of |a| measured), which a run keeps.
    std::vector<bool> fixed(static_cast<std::size_t>(model.dof_count()), true);
    for (int k = 0; k < model.T.outerSize(); ++k)
        for (SparseMatrix::InnerIterator it(model.T, k); it; ++it)
            if (it.value() != 0.0) fixed[static_cast<std::size_t>(it.row())] = false;
    const Vector off_surface = s.u - model.T * (model.T.transpose() * s.u);
    const std::array<std::pair<const Vector*, const char*>, 3> motions{{{&s.u, "displacement"}, {&s.v, "velocity"}, {&s.a, "acceleration"}}};
    for (const auto& [x, what] : motions)
        for (Eigen::Index i = 0; i < x->size(); ++i) {
            const bool held = fixed[static_cast<std::size_t>(i)] ? (*x)[i] == 0.0
                            : x != &s.u || std::abs(off_surface[i]) <= 1e-9 * std::max(s.u.lpNorm<Eigen::Infinity>(), model.characteristic_length);
            if (!held)
                throw protocol::SolverError("bad_config", std::string("structure: the checkpoint gives node ") + std::to_string(i / 3) +
                                                              " a " + what + " its supports do not allow; the file is damaged");
        }
    return s;
}

}  // namespace sphfsi::structure
