// Simulation2D: diagnostics of the state (free surface, energy, memory), the in-memory save/restore of
// implicit coupling and the byte checkpoints that resume a run bit-identically.
#include "sphfsi/fluid/simulation.hpp"

#include <cmath>
#include <string>
#include <type_traits>
#include <utility>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {
namespace {

using protocol::SolverError;

constexpr std::uint64_t checkpoint_magic = 0x3146495346485053ULL;  // "SPHFSIF1"

[[noreturn]] void refuse(const std::string& what) {
    throw SolverError("bad_config", "checkpoint: " + what + "; the file is damaged or was not written for this scene");
}

template <class T>
void check_size(const std::vector<T>& a, std::size_t want, const char* name) {
    if (a.size() != want)
        refuse(std::string(name) + " has " + std::to_string(a.size()) + " entries for " + std::to_string(want) + " particles");
}

template <class T>
void check_finite(const std::vector<T>& a, const char* name) {
    for (std::size_t i = 0; i < a.size(); ++i) {
        bool finite = true;
        if constexpr (std::is_arithmetic_v<T>) finite = std::isfinite(a[i]);
        else for (double c : a[i].c) finite = finite && std::isfinite(c);
        if (!finite) refuse(std::string(name) + " of entry " + std::to_string(i) + " is not a finite number");
    }
}

// Everything a restored state's later steps index with or divide by is checked here, once: the header's
// counts matched the scene, but a damaged array (one entry short, an id out of range, a kind that does not
// exist, a NaN) had been accepted with READY and crashed the first step or snapshot (a review, 2026-11-27).
template <class State, class V>
void check_restored_state(const State& st, std::size_t n, std::size_t n_fluid, std::size_t n_solid,
                          const std::vector<V>& solid_acc) {
    const auto& P = st.P;
    check_size(P.x, n, "position"); check_size(P.v, n, "velocity"); check_size(P.rho, n, "density"); check_size(P.id, n, "id");
    check_size(P.tag, n, "tag"); check_size(P.kind, n, "kind"); check_size(P.a, n, "acceleration");
    check_size(P.drho, n, "density rate"); check_size(P.p, n, "pressure"); check_size(P.v_visc, n, "viscous velocity");
    check_size(P.div_r, n, "position divergence");
    check_size(solid_acc, n_solid, "solid acceleration");
    check_size(st.solid_force_sum, n_solid, "solid force sum");
    std::vector<bool> seen(n, false);
    for (std::int32_t id : P.id) {
        if (id < 0 || static_cast<std::size_t>(id) >= n || seen[static_cast<std::size_t>(id)])
            refuse("the particle ids are not 0 to " + std::to_string(n - 1) + " each once (id " + std::to_string(id) + ")");
        seen[static_cast<std::size_t>(id)] = true;
    }
    std::size_t count[4] = {0, 0, 0, 0};
    for (Kind k : P.kind) {
        const auto c = static_cast<std::int8_t>(k);
        if (c < 0 || c > 3) refuse("a particle has kind " + std::to_string(c) + "; kinds are 0 to 3");
        ++count[static_cast<std::size_t>(c)];
    }
    if (count[0] + count[3] != n_fluid || count[2] != n_solid || count[3] != st.escaped)
        refuse("its particle kinds (" + std::to_string(count[0]) + " fluid, " + std::to_string(count[3]) + " escaped of " +
               std::to_string(st.escaped) + ", " + std::to_string(count[2]) + " solid) do not match its counts (" +
               std::to_string(n_fluid) + " fluid, " + std::to_string(n_solid) + " solid)");
    check_finite(P.x, "position"); check_finite(P.v, "velocity"); check_finite(P.rho, "density");
    check_finite(P.a, "acceleration"); check_finite(P.drho, "density rate"); check_finite(P.p, "pressure");
    check_finite(P.v_visc, "viscous velocity"); check_finite(P.div_r, "position divergence");
    check_finite(solid_acc, "solid acceleration"); check_finite(st.solid_force_sum, "solid force sum");
    for (const auto& [value, name] : {std::pair{st.t, "time"}, {st.a_max, "largest acceleration"},
                                      {st.u_max, "largest speed"}, {st.rho_max, "largest density"},
                                      {st.a_max_last, "last largest acceleration"}, {st.solid_weight, "solid weight"}})
        if (!std::isfinite(value)) refuse(std::string("its ") + name + " is not a finite number");
}

}  // namespace

std::size_t Simulation2D::free_surface_count() const {
    const auto& P = st_.P;
    const float threshold = surface_threshold();
    std::size_t n = 0;
    for (std::size_t i = 0; i < P.size(); ++i) n += P.kind[i] == Kind::Fluid && P.div_r[i] < threshold;
    return n;
}

Simulation2D::Energy Simulation2D::mechanical_energy() const {
    const auto& P = st_.P;
    V g{};
    for (int k = 0; k < Dim; ++k) g[k] = s_.gravity[static_cast<std::size_t>(k)];
    Energy e;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        e.kinetic += 0.5 * mass_ * norm2(P.v[i]);
        e.potential -= mass_ * dot(g, P.x[i]);
    }
    return e;
}

std::size_t Simulation2D::memory_bytes() const {
    return st_.P.memory_bytes() + (has_saved_ ? saved_.P.memory_bytes() : 0) + grid_.memory_bytes() +
           order_.capacity() * sizeof(std::uint32_t) + scratch_.capacity() + rho_scratch_.capacity() * sizeof(double) +
           pci_.memory_bytes() + (correction_.capacity() + saved_correction_.capacity()) * sizeof(Mat<Dim>);
}

// The kept rates were made with the correction matrices L of their evaluation, which the window-start shortcut
// compares the new L with (refresh_solid_rates): L goes with the state. Without it, after RESTORE the shortcut
// compared with the last iterate's L, so a repeated iterate did not repeat, and after a resume L was empty and
// the first window read past it (SIGSEGV); evaluating afresh instead changed resumed runs, the shortcut being
// no full evaluation for a fluid alone or velocity Verlet (reviews, 2026-11-27).
void Simulation2D::save() {
    saved_ = st_;
    saved_correction_ = correction_;
    has_saved_ = true;
}

void Simulation2D::restore() {
    if (!has_saved_) throw SolverError("bad_state", "RESTORE before any SAVE");
    st_ = saved_;
    stepping_ = false;  // a step that failed part-way left its marks; the saved state is between steps
    density_dt_at_evaluation_ = 0.0;
    correction_ = saved_correction_;
    rates_.correction = correction_.data();
    sort_particles();  // the grid belongs to the state it was built for; the saved particles are already in cell order
}

void Simulation2D::write_state(ByteWriter& w) const {
    const auto& P = st_.P;
    w.put(checkpoint_magic);
    w.put<std::uint64_t>(P.size());
    w.put<std::uint64_t>(n_fluid_);
    w.put<std::uint64_t>(n_solid_);
    w.put(st_.t);
    w.put(st_.step);
    w.put<std::uint8_t>(st_.rates_fresh ? 1 : 0);
    w.put(st_.a_max);
    w.put(st_.u_max);
    w.put(st_.rho_max);
    w.put(st_.a_max_last);
    w.put(st_.escaped);
    w.put_vector(P.x); w.put_vector(P.v); w.put_vector(P.rho); w.put_vector(P.id); w.put_vector(P.tag);
    w.put_vector(P.kind); w.put_vector(P.a); w.put_vector(P.drho); w.put_vector(P.p); w.put_vector(P.v_visc);
    w.put_vector(P.div_r);
    w.put_vector(solid_acc_);
    w.put_vector(st_.solid_force_sum);
    w.put(st_.solid_weight);
    w.put_vector(correction_);  // empty without the pressure correction
}

void Simulation2D::read_state(ByteReader& r, bool with_correction) {
    auto& P = st_.P;
    if (r.get<std::uint64_t>() != checkpoint_magic) throw SolverError("bad_config", "checkpoint: not a sphfsi-fluid state");
    const auto n = r.get<std::uint64_t>(), nf = r.get<std::uint64_t>(), ns = r.get<std::uint64_t>();
    if (n != P.size() || nf != n_fluid_ || ns != n_solid_)
        throw SolverError("bad_config", "checkpoint: it holds " + std::to_string(n) + " particles (" + std::to_string(nf) +
                                            " fluid, " + std::to_string(ns) + " solid) but this scene makes " +
                                            std::to_string(P.size()) + " (" + std::to_string(n_fluid_) + ", " +
                                            std::to_string(n_solid_) + "): resume with the scene that wrote it");
    st_.t = r.get<double>();
    st_.step = r.get<std::uint64_t>();
    const auto fresh = r.get<std::uint8_t>();
    if (fresh > 1) refuse("its rates flag is " + std::to_string(fresh) + ", not 0 or 1");
    st_.rates_fresh = fresh != 0;
    st_.a_max = r.get<double>();
    st_.u_max = r.get<double>();
    st_.rho_max = r.get<double>();
    st_.a_max_last = r.get<double>();
    st_.escaped = r.get<std::uint64_t>();
    r.get_vector(P.x); r.get_vector(P.v); r.get_vector(P.rho); r.get_vector(P.id); r.get_vector(P.tag);
    r.get_vector(P.kind); r.get_vector(P.a); r.get_vector(P.drho); r.get_vector(P.p); r.get_vector(P.v_visc);
    r.get_vector(P.div_r);
    r.get_vector(solid_acc_);
    r.get_vector(st_.solid_force_sum);
    st_.solid_weight = r.get<double>();
    check_restored_state(st_, n, n_fluid_, n_solid_, solid_acc_);
    correction_.clear();
    if (with_correction) r.get_vector(correction_);
    // Kept rates need their L, one per particle; without the pressure correction there is none.
    const bool fits = s_.kernel_correction ? correction_.size() == n || (!st_.rates_fresh && correction_.empty())
                                           : correction_.empty();
    if (with_correction && !fits)
        refuse("it holds " + std::to_string(correction_.size()) + " correction matrices for " + std::to_string(n) +
               " particles (the pressure correction is " + (s_.kernel_correction ? "on" : "off") + ")");
    for (const auto& L : correction_)
        for (double x : L)
            if (!std::isfinite(x)) refuse("a correction matrix holds a value that is not a finite number");
    // An older (SPHFSIP2) state has no L: its rates are evaluated afresh, the most a resume of it can do.
    if (!with_correction && s_.kernel_correction) st_.rates_fresh = false;
    rates_.correction = correction_.data();
    sort_particles();  // rebuild the grid for the restored positions (already in cell order: no reordering)
}

}  // namespace sphfsi::fluid
