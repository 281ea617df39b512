#pragma once
// Structure-of-arrays particle storage. Every per-particle quantity is its own contiguous array so a pass
// touches only what it needs; vectors are stored as Vec<Dim> (x and y of one particle together, as every
// pass needs both). The arrays are kept in cell order (see CellGrid) and reordered together by reorder().
// `id` is the particle's original index, so outputs can be written in a stable order.
#include <cstdint>
#include <cstring>
#include <vector>

#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

// Escaped: a fluid particle that left an open tank over the top of a side wall. It is frozen where it
// left and taken out of the neighbour search (see CellGrid::build), so it no longer takes part in anything.
enum class Kind : std::int8_t { Fluid = 0, Wall = 1, Solid = 2, Escaped = 3 };

inline bool is_boundary(Kind k) { return k == Kind::Wall || k == Kind::Solid; }

template <int Dim>
struct ParticleStore {
    using V = Vec<Dim>;
    // State (what a checkpoint holds).
    std::vector<V> x;             // position [m]
    std::vector<V> v;             // velocity [m/s]; walls: their prescribed velocity
    std::vector<double> rho;      // density [kg/m^3]
    std::vector<std::int32_t> id; // original index
    std::vector<std::int32_t> tag;  // dye
    std::vector<Kind> kind;
    // Rates from the last evaluation (kept: velocity Verlet starts a step with them).
    std::vector<V> a;             // acceleration [m/s^2]
    std::vector<double> drho;     // density rate [kg/m^3/s]
    // Derived each evaluation.
    std::vector<double> p;        // pressure [Pa]
    std::vector<V> v_visc;        // wall/solid: velocity seen by viscous terms (Adami no-slip ghost velocity)
    std::vector<float> div_r;     // divergence of position, free-surface indicator
    // Integrator copies of the step start (allocated only by integrators that need them).
    std::vector<V> x_start, v_start;
    std::vector<double> rho_start;

    std::size_t size() const { return x.size(); }

    void resize(std::size_t n) {
        x.resize(n); v.resize(n); rho.resize(n); id.resize(n); tag.resize(n); kind.resize(n);
        a.resize(n); drho.resize(n); p.resize(n); v_visc.resize(n); div_r.resize(n);
    }

    // Applies order[new] = old to every array, using `scratch` as the staging buffer (no allocation in the
    // steady state: the buffer keeps its capacity).
    void reorder(const std::vector<std::uint32_t>& order, std::vector<unsigned char>& scratch) {
        permute(x, order, scratch); permute(v, order, scratch); permute(rho, order, scratch);
        permute(id, order, scratch); permute(tag, order, scratch); permute(kind, order, scratch);
        permute(a, order, scratch); permute(drho, order, scratch); permute(p, order, scratch);
        permute(div_r, order, scratch);
        // v_visc is recomputed after every sort, so it is not carried along.
        if (!x_start.empty()) permute(x_start, order, scratch);
        if (!v_start.empty()) permute(v_start, order, scratch);
        if (!rho_start.empty()) permute(rho_start, order, scratch);
    }

    std::size_t memory_bytes() const {
        return (x.capacity() + v.capacity() + a.capacity() + v_visc.capacity() + x_start.capacity() + v_start.capacity()) * sizeof(V) +
               (rho.capacity() + drho.capacity() + p.capacity() + rho_start.capacity()) * sizeof(double) +
               (id.capacity() + tag.capacity()) * sizeof(std::int32_t) + kind.capacity() + div_r.capacity() * sizeof(float);
    }

    template <class T>
    static void permute(std::vector<T>& a, const std::vector<std::uint32_t>& order, std::vector<unsigned char>& scratch) {
        const std::size_t n = a.size();
        if (scratch.size() < n * sizeof(T)) scratch.resize(n * sizeof(T));
        T* tmp = reinterpret_cast<T*>(scratch.data());
        const long long nn = static_cast<long long>(n);
#pragma omp parallel for schedule(static)
        for (long long k = 0; k < nn; ++k) tmp[k] = a[order[static_cast<std::size_t>(k)]];
        std::memcpy(static_cast<void*>(a.data()), tmp, n * sizeof(T));
    }
};

}  // namespace sphfsi::fluid
