#pragma once
// PCISPH pressure solve (Solenthaler & Pajarola 2009). Given the non-pressure accelerations a_np at time t,
// pressures are found iteratively: predict velocities and positions with the current pressure force,
// predict densities by summation at the predicted positions, and raise each particle's pressure by
// delta * (rho* - rho0) with the precomputed stiffness
//   delta = rho0^2 / (2 dt^2 m m_sum (|sum_j grad W_ij|^2 + sum_j |grad W_ij|^2))  (Solenthaler & Pajarola's
//   form, on a filled prototype neighbourhood of the dp lattice, where the first sum vanishes),
// until the largest predicted density error is below eta * rho0 after at least `min_iterations` corrections.
// The pressure force is a_i = -sum_j m (p_i + p_j) / rho0^2 grad W_ij at the positions of time t (the form
// the stiffness delta is derived for), summed over a list of its pairs built once per step (gradient_pairs.hpp).
// Neighbour lists are those of time t: predicted positions move a small fraction of h per step, so pairs
// entering the support during the step are at its very edge.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <omp.h>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/gradient_pairs.hpp"
#include "sphfsi/fluid/lattice.hpp"
#include "sphfsi/fluid/particles.hpp"

namespace sphfsi::fluid {

template <int Dim>
struct PcisphParams {
    double mass = 0.0, rho0 = 1000.0, eta = 0.01;
    double summation_mass = 0.0;  // the mass in the predicted densities' kernel sums (Simulation2D says why)
    int min_iterations = 3, max_iterations = 50;
    bool clamp_negative = true;   // free surface: only compression is corrected, pressures stay >= 0
    bool dummy_boundaries = false;  // dummy walls are corrected like fluid; otherwise Adami extrapolation
    double delta_dt2 = 0.0;       // delta * dt^2 (divide by dt^2 for the step's delta)
};

template <int Dim>
struct PcisphScratch {
    std::vector<Vec<Dim>> x_pred, a_p;
    std::vector<double> rho_pred;
    GradientPairs<Dim> pairs;  // the pressure force's pairs at the positions of time t
    void resize(std::size_t n) { x_pred.resize(n); a_p.resize(n); rho_pred.resize(n); }
    std::size_t memory_bytes() const {
        return x_pred.capacity() * sizeof(Vec<Dim>) * 2 + rho_pred.capacity() * sizeof(double) + pairs.memory_bytes();
    }
};

struct PcisphOutcome {
    int iterations = 0;              // pressure corrections applied
    double max_density_error = 0.0;  // of the accepted prediction, as a fraction of rho0
    bool converged = false;
};

// Stiffness factor delta * dt^2 from a prototype fluid particle with a full lattice neighbourhood: the
// pressure force carries the particle mass m, the predicted density the summation mass m_sum.
template <int Dim, class KernelG>
double pcisph_delta_dt2(const KernelG& kg, double dp, double mass, double summation_mass, double rho0) {
    double sum_grad2 = 0.0;
    Vec<Dim> sum_grad{};
    for_each_lattice_neighbour<Dim>(dp, kg.support(), [&](const Vec<Dim>& dx, double r) {
        const Vec<Dim> g = dx * kg.grad_factor(r);
        sum_grad += g;
        sum_grad2 += norm2(g);
    });
    const double beta = 2.0 * mass * summation_mass / (rho0 * rho0);  // times dt^2
    return -1.0 / (beta * (-norm2(sum_grad) - sum_grad2));
}

// Runs the correction loop for a step of length dt. P.a holds a_np for fluid and solid particles (read
// only) and s.x_pred holds the end-of-step positions of boundary particles. On success P.p holds the
// pressures, s.a_p the pressure accelerations and s.x_pred / s.rho_pred the accepted prediction.
template <int Dim, class KernelW, class KernelG, class BoundaryPressure>
PcisphOutcome pcisph_solve(ParticleStore<Dim>& P, const CellGrid<Dim>& grid, const KernelW& kw, const KernelG& kg,
                           const PcisphParams<Dim>& prm, double dt, PcisphScratch<Dim>& s,
                           BoundaryPressure&& boundary_pressure) {
    using V = Vec<Dim>;
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    const double R2 = grid.radius2(), m = prm.mass, delta = prm.delta_dt2 / (dt * dt);
    const double inv_rho02 = 1.0 / (prm.rho0 * prm.rho0), w0 = kw.w(0.0);
#pragma omp parallel for schedule(static)
    for (long long k = 0; k < nn; ++k) {
        const std::size_t i = static_cast<std::size_t>(k);
        s.a_p[i] = V{};
        P.p[i] = 0.0;
    }
    // Every correction sums the pressure force over the same pairs at the same positions: list them once.
    s.pairs.build(grid, P.x, n, kg, [&](std::uint32_t i) { return P.kind[i] != Kind::Wall; },
                  [&](std::uint32_t i, std::uint32_t j) { return P.kind[i] == Kind::Fluid || P.kind[j] == Kind::Fluid; });
    PcisphOutcome out;
    for (int it = 0;; ++it) {
        // Predict positions of fluid particles (boundaries were set by the caller).
#pragma omp parallel for schedule(static)
        for (long long k = 0; k < nn; ++k) {
            const std::size_t i = static_cast<std::size_t>(k);
            if (P.kind[i] == Kind::Fluid) s.x_pred[i] = P.x[i] + (P.v[i] + (P.a[i] + s.a_p[i]) * dt) * dt;
        }
        // Predicted densities and the largest error.
        std::vector<double> thread_max(static_cast<std::size_t>(omp_get_max_threads()), 0.0);
        grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
            typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
            const int nr = grid.ranges(cell, ranges);
            double local_max = 0.0;
            for (std::uint32_t i = begin; i < end; ++i) {
                const bool fluid = P.kind[i] == Kind::Fluid;
                if (!fluid && !prm.dummy_boundaries) continue;
                const V xi = s.x_pred[i];
                double sum = w0;
                for (int r = 0; r < nr; ++r)
                    for (std::uint32_t j = ranges[r].begin; j < ranges[r].end; ++j) {
                        const double r2 = norm2(xi - (s.x_pred[j] + ranges[r].shift));
                        if (r2 < R2 && j != i) sum += kw.w(std::sqrt(r2));
                    }
                s.rho_pred[i] = prm.summation_mass * sum;
                if (fluid) {
                    const double e = s.rho_pred[i] - prm.rho0;
                    local_max = std::max(local_max, prm.clamp_negative ? e : std::abs(e));
                }
            }
            double& tm = thread_max[static_cast<std::size_t>(omp_get_thread_num())];
            tm = std::max(tm, local_max);
        });
        const double max_err = *std::max_element(thread_max.begin(), thread_max.end());
        out.max_density_error = max_err / prm.rho0;
        if (out.iterations >= prm.min_iterations && out.max_density_error < prm.eta) {
            out.converged = true;
            return out;
        }
        if (out.iterations >= prm.max_iterations) return out;
        // Correct pressures.
#pragma omp parallel for schedule(static)
        for (long long k = 0; k < nn; ++k) {
            const std::size_t i = static_cast<std::size_t>(k);
            const bool fluid = P.kind[i] == Kind::Fluid;
            if (!fluid && !(prm.dummy_boundaries && is_boundary(P.kind[i]))) continue;
            double p = P.p[i] + delta * (s.rho_pred[i] - prm.rho0);
            if (prm.clamp_negative || !fluid) p = std::max(p, 0.0);
            P.p[i] = p;
        }
        if (!prm.dummy_boundaries) boundary_pressure();
        // Pressure accelerations at the positions of time t (fluid, and the reaction on solids), over the pairs
        // listed before the loop: the same terms in the same order as a scan of the cells. Which particles and
        // pairs take part is the list's rule alone (walls have no pairs, so theirs stay zero).
        const bool periodic = !s.pairs.shift.empty();
#pragma omp parallel for schedule(static)
        for (long long k = 0; k < nn; ++k) {
            const std::size_t i = static_cast<std::size_t>(k);
            const V xi = P.x[i];
            const double pi = P.p[i];
            V acc{};
            for (std::size_t q = s.pairs.first[i]; q < s.pairs.first[i + 1]; ++q) {
                const std::uint32_t j = s.pairs.j[q];
                const V dx = xi - (periodic ? P.x[j] + s.pairs.shift[q] : P.x[j]);
                acc += dx * (-(pi + P.p[j]) * s.pairs.grad_factor[q]);
            }
            s.a_p[i] = acc * (m * inv_rho02);
        }
        ++out.iterations;
    }
}

}  // namespace sphfsi::fluid
