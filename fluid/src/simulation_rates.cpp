// Simulation2D: evaluation of the rates (accelerations, density rates, pressures) at the current state,
// and the stable step they allow.
#include "sphfsi/fluid/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "format.hpp"
#include "sphfsi/fluid/density_summation.hpp"
#include "sphfsi/fluid/kernel_dispatch.hpp"
#include "sphfsi/fluid/wall_boundary.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {

using protocol::SolverError;

// Fluid and walls only: solid particles stay where the structure puts them (move_solids, and PCISPH's
// predicted positions, come from its kinematics), inside the period (check_inside_tank).
void Simulation2D::wrap_periodic() {
    auto& P = st_.P;
    for (int k = 0; k < Dim; ++k) {
        if (!s_.periodic[static_cast<std::size_t>(k)]) continue;
        const double lo = domain_lo_[k], len = domain_hi_[k] - domain_lo_[k];
        const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
        for (long long q = 0; q < n; ++q) {
            if (P.kind[static_cast<std::size_t>(q)] == Kind::Solid) continue;
            double& x = P.x[static_cast<std::size_t>(q)][k];
            if (x < lo || x >= lo + len) {
                x -= std::floor((x - lo) / len) * len;
                if (x >= lo + len) x = lo;  // rounding of a value just below lo
            }
        }
    }
}

void Simulation2D::move_solids(double t) {
    if (n_solid_ == 0 || !kinematics_) return;
    auto& P = st_.P;
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] != Kind::Solid) continue;
        const std::size_t k = static_cast<std::size_t>(P.id[i] - first_solid_id_);
        kinematics_(k, t, P.x[i], P.v[i], solid_acc_[k]);
    }
}

void Simulation2D::sort_particles() {
    wrap_periodic();
    const Kind* kind = st_.P.kind.data();
    grid_.build(st_.P.x, order_, [kind](std::size_t i) { return kind[i] == Kind::Escaped; });
    bool identity = true;
    for (std::size_t k = 0; k < order_.size() && identity; ++k) identity = order_[k] == k;
    if (!identity) st_.P.reorder(order_, scratch_);
}

Simulation2D::V Simulation2D::boundary_acceleration(std::uint32_t w) const {
    const auto& P = st_.P;
    if (P.kind[w] != Kind::Solid) return V{};
    return solid_acc_[static_cast<std::size_t>(P.id[w] - first_solid_id_)];
}

template <class KernelW>
void Simulation2D::sum_densities(const KernelW& kw, bool cspm) {
    // Written in place: a particle's sum reads no density but its own (a boundary particle keeps it).
    const std::vector<double>* volumes = nullptr;
    if (cspm) {
        summation_density(st_.P, grid_, kw, summation_mass_, true, nullptr, rho_scratch_);  // plain sums: the volumes
        volumes = &rho_scratch_;
    }
    summation_density(st_.P, grid_, kw, summation_mass_, s_.wall == WallModel::Dummy, volumes, st_.P.rho);
}

void Simulation2D::reinitialise_densities() {
    // Integrated densities drift away from what the particles' spacing says over long runs (the wind basin's
    // lee-wall ridge, docs/validation.md): replace them by the CSPM sums of the positions now held, fluid and,
    // in the dummy model (whose walls integrate densities too), boundary particles. CSPM, not the plain
    // sums, although it is the lower of the two in the surface's second and third rows (density_summation.hpp):
    // re-initialised from plain sums the wind basin's profile was 3.0 % off over t = 6 - 8 s, against 1.9 %
    // (docs/validation.md, "Wind-driven closed basin"). The step's rates belong to
    // the old densities, so the next step evaluates afresh. Checkpoints keep the step count: a resumed run
    // re-initialises at the same steps.
    move_solids(st_.t);
    sort_particles();
    with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto&) { sum_densities(kw, true); });
    st_.rates_fresh = false;
}

void Simulation2D::evaluate() {
    auto& P = st_.P;
    move_solids(st_.t);
    sort_particles();
    integrate_densities(std::exchange(density_dt_at_evaluation_, 0.0));
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    const bool pcisph = s_.pressure == PressureModel::Pcisph;
    const bool dummy = s_.wall == WallModel::Dummy;
    const bool summation = s_.density != DensityMethod::Continuity;
    with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto& kg) {
        if (summation) {
            sum_densities(kw, s_.density == DensityMethod::Shepard);
            check_summed_densities();
        }
        // Pressures of fluid particles and (dummy model) boundary particles from the equation of state.
        // PCISPH's pressures come from its solve in the step; P.p keeps those of the last step taken (zero
        // before the first), which is what the record shows, and fill_rate_factors leaves them out of
        // these rates, which are PCISPH's non-pressure accelerations.
        const bool tait = s_.pressure == PressureModel::Wcsph;
#pragma omp parallel for schedule(static)
        for (long long q = 0; q < nn; ++q) {
            const std::size_t i = static_cast<std::size_t>(q);
            const bool fluid = P.kind[i] == Kind::Fluid;
            if (!fluid && !(dummy && is_boundary(P.kind[i]))) continue;  // Adami: extrapolated below
            if (!pcisph) {
                double p = tait ? tait_.pressure(P.rho[i]) : standard_.pressure(P.rho[i]);
                // A dummy wall particle never pulls fluid onto the wall (Adami walls follow clamp_negative:
                // extrapolate_boundary_state); fluid may be clamped by choice.
                if (!fluid || s_.clamp_negative) p = std::max(p, 0.0);
                P.p[i] = p;
            }
            if (!fluid) P.v_visc[i] = P.v[i];
        }
        if (!dummy)
            extrapolate_boundary_state(P, grid_, kw, rates_.gravity, s_.clamp_negative,
                                       [&](double p) { return boundary_density(p); },
                                       [&](std::uint32_t w) { return boundary_acceleration(w); });
        KinematicFloor floor;
        if (kinematic_floor_) {
            rho_scratch_.resize(n);
            floor = KinematicFloor{kinematic_cap_, summation_mass_, rho_scratch_.data()};
        }
        update_correction(kg);
        compute_rates(P, grid_, kw, kg, ViscosityKernel<Dim>(h_), fill_rate_factors(), rates_,
                      kinematic_floor_ ? &floor : nullptr);
        // The free surface where it meets a tank wall, mirrored (surface_stress.hpp), only where the wind
        // needs it. Elsewhere the record's flag and the kernel correction's full-support mask would read it,
        // the mask only where the two counts differ next to a tank wall, and no scene without wind corrects;
        // it cost the a/40 dam break 6.6 % of its compute time (WCSPH, one thread, medians of 3: 10.43 s
        // against 9.78 s).
        if (surface_.on()) {
            detect_surface_at_tank_walls(P, grid_, kg, mass_, surface_);
            wind_surface_ = apply_surface_stress(P, grid_, kg, mass_, surface_);
        }
        if (kinematic_floor_) {
#pragma omp parallel for schedule(static)
            for (long long q = 0; q < nn; ++q) {
                const std::size_t i = static_cast<std::size_t>(q);
                P.rho[i] = std::max(P.rho[i], rho_scratch_[i]);
            }
        }
    });
    reduce_rates();
    st_.rates_fresh = true;
}

const RateFactors* Simulation2D::fill_rate_factors() {
    const auto& P = st_.P;
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    if (scratch_.size() < n * sizeof(RateFactors)) scratch_.resize(n * sizeof(RateFactors));
    RateFactors* factors = reinterpret_cast<RateFactors*>(scratch_.data());
    const bool pcisph = s_.pressure == PressureModel::Pcisph;  // its pressure force comes from its solve
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < nn; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        factors[i] = RateFactors{pcisph ? 0.0 : P.p[i] / (P.rho[i] * P.rho[i]), 1.0 / P.rho[i]};
    }
    return factors;
}

// A wall pressure below the equation of state's vacuum (p < p_b - B for Tait, -k rho0 for the ideal gas;
// reachable with negative pressures kept and a small c0) inverts to a density of 0 or below, and 1/rho in the
// pair terms then made the fluid's accelerations infinite, reported as a non-finite fluid velocity (a review,
// 2026-11-27). A wall particle's density is held at the fluid's own lower bound, failure.min_density_ratio,
// and at 0.01 rho0 where that bound is set to 0.
double Simulation2D::boundary_density(double p) const {
    if (s_.pressure == PressureModel::Pcisph) return s_.rho0;
    const double rho = s_.pressure == PressureModel::Wcsph ? tait_.density(p) : standard_.density(p);
    return std::max(rho, (s_.min_density_ratio > 0.0 ? s_.min_density_ratio : 0.01) * s_.rho0);
}

// A coupling window starts: the solid particles take the new window's kinematics, and the rates that start
// the window's first step must be those of the new window's wall acceleration.
//
// Why. The rates at the window start were evaluated at the end of the previous window (for the dt_wanted
// of the reply, or by velocity Verlet's closing evaluation) and are kept as fresh: the particles have not
// moved since. But they were evaluated with the previous window's kinematics, and one thing in them depends
// on the window: the Adami wall pressure of a solid particle, p_w = (sum_f p_f W + (g - a_w) . sum_f rho_f
// (x_w - x_f) W) / sum_f W, holds the solid's acceleration a_w = (v1 - v0) / dt over the window (the
// interface moves with a constant acceleration between the window-start and window-end velocities). With
// the stale rates, the first step of a window, and with one fluid step per window (the thesis rule) the
// whole window, pushed the fluid and reported the force with the previous window's a_w: the fluid's force
// did not depend on this window's structure iterate at all, an implicit coupling converged in one update
// and it felt the fluid's added mass one window late, which is no more stable than an explicit scheme
// (docs/validation.md, "Added mass").
//
// What is right. In the semi-implicit (symplectic) Euler step v^{n+1} = v^n + dt a(x^n), the fluid next to
// the wall must accelerate with the wall over the same step: the pressure's wall condition
// dp/dn = rho (g - a_w) . n is the step's Neumann condition, and a_w is the wall's velocity change over
// this step, (v1 - v0) / dt of the window the step lies in. The positions and velocities of the solid at
// the step's start are the window's start values, known before the window. So the force of the window is
// evaluated at the start-of-window state with the window's own (iterated) wall acceleration; the same rates
// kick the fluid, so the force reported is still exactly minus the fluid's momentum change from the solids
// (momentum is conserved across the interface), and after RESTORE each iterate gets its own a_w. (Reporting
// the end-of-window force instead would make the force depend on the iterate too, but it is not the force
// that moved the fluid.) The wall acceleration term is the instantaneous part of the added mass: about the
// fluid within a kernel support of the wall, which is also what a compressible fluid can add within one
// step (rho_f c dt with dt = CFL h / c).
//
// How. Only the solids' extrapolated pressure and density change, so only the solid particles and the fluid
// particles within a support of one are recomputed, each exactly as a full evaluation would (same state,
// same neighbour order); for symplectic Euler and predictor-corrector nothing else has changed since the
// end-of-window evaluation, so the rates are those of a full evaluation at a fraction of its cost. (Velocity Verlet's closing evaluation saw v^{n+1/2}; the recomputed particles see v^{n+1}, as
// a full evaluation at the window start would.) With the pressure correction the solids' densities also
// enter the matrices L of their fluid neighbours, and through the pair terms (L_i + L_j)/2 the rates of those
// neighbours' neighbours: that second ring is recomputed too (tests/fluid/test_adapter.cpp compares the
// shortcut with a full evaluation bit for bit). With dummy walls (no a_w in the wall pressure) and PCISPH
// (a_w enters its pressure solve, which reads it from solid_acc_) nothing else needs recomputing.
// Not exact with the kinematic density floor: the densities it raised after the last pass enter the
// recomputed viscous terms but not the kept ones of the fluid beyond, so the solids' forces and the fluid's
// reaction differ slightly (2.6e-6 of the force measured; docs/coupling.md says why it is left).
void Simulation2D::refresh_solid_rates() {
    if (n_solid_ == 0 || !kinematics_ || !st_.rates_fresh) return;  // else the first step evaluates anyway
    auto& P = st_.P;
    const std::size_t n = P.size();
    solid_xv_.clear();
    for (std::size_t i = 0; i < n; ++i)
        if (P.kind[i] == Kind::Solid) {
            solid_xv_.push_back(P.x[i]);
            solid_xv_.push_back(P.v[i]);
        }
    move_solids(st_.t);
    bool same = true;
    for (std::size_t i = 0, k = 0; i < n && same; ++i)
        if (P.kind[i] == Kind::Solid) {
            same = P.x[i] == solid_xv_[k] && P.v[i] == solid_xv_[k + 1];
            k += 2;
        }
    if (!same) {  // the window does not start where the last one ended (not the case in a coupled run)
        evaluate();
        return;
    }
    if (s_.wall == WallModel::Dummy || s_.pressure == PressureModel::Pcisph) return;
    near_solid_.assign(n, 0);
    with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto& kg) {
        extrapolate_boundary_state(P, grid_, kw, rates_.gravity, s_.clamp_negative,
                                   [&](double p) { return boundary_density(p); },
                                   [&](std::uint32_t w) { return boundary_acceleration(w); }, true);
        // Marks with `ring` each unmarked fluid particle within the support of a particle `source(i)` picks
        // (a hair beyond the support: marking one too many costs nothing, it is recomputed to the same value).
        const double R2 = grid_.radius2() * (1.0 + 1e-9);
        auto mark_fluid_neighbours = [&](const auto& source, std::uint8_t ring) {
            grid_.for_each_cell([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
                typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
                int nr = -1;
                for (std::uint32_t i = begin; i < end; ++i) {
                    if (!source(i)) continue;
                    if (nr < 0) nr = grid_.ranges(cell, ranges);
                    for (int r = 0; r < nr; ++r)
                        for (std::uint32_t f = ranges[r].begin; f < ranges[r].end; ++f)
                            if (P.kind[f] == Kind::Fluid && !near_solid_[f] && norm2(P.x[i] - (P.x[f] + ranges[r].shift)) < R2)
                                near_solid_[f] = ring;
                }
            });
        };
        // The solids and their fluid neighbours.
        for (std::size_t i = 0; i < n; ++i)
            if (P.kind[i] == Kind::Solid) near_solid_[i] = 1;
        mark_fluid_neighbours([&](std::uint32_t i) { return P.kind[i] == Kind::Solid; }, 1);
        // A second ring, the fluid neighbours of the first: with the correction, the solids' new densities
        // change the matrices L of their fluid neighbours, and the pair terms (L_i + L_j)/2 of those
        // neighbours' own neighbours with them; with wind, a first-ring particle whose surface flag flips here
        // changes the shares of the surface particles within reach of it (a review, 2026-11-29: without the
        // correction the refresh kept theirs, and a window ended apart from a full evaluation's).
        if (s_.kernel_correction || surface_.on())
            mark_fluid_neighbours([&](std::uint32_t i) { return near_solid_[i] == 1 && P.kind[i] == Kind::Fluid; }, 2);
        if (s_.kernel_correction) {
            // L is built on the mask of the evaluation before it (P.div_r): the window-end evaluation used the
            // one before that, a full evaluation now would use the window end's. Where the free surface moved,
            // masks flip far from any solid (a review, 2026-11-27), so every particle whose L comes out
            // different is recomputed too, with its neighbours, whichever ring it is in (a second-ring
            // particle's neighbours are in no ring of their own).
            correction_kept_ = correction_;
            update_correction(kg);
            auto changed = [&](std::uint32_t i) { return correction_[i] != correction_kept_[i]; };
            for (std::size_t i = 0; i < n; ++i)
                if (!near_solid_[i] && changed(static_cast<std::uint32_t>(i))) near_solid_[i] = 3;
            mark_fluid_neighbours(changed, 4);
        }
        // The factors of all particles: the buffer is scratch (the sort reuses it), not state.
        compute_rates(P, grid_, kw, kg, ViscosityKernel<Dim>(h_), fill_rate_factors(), rates_, nullptr,
                      near_solid_.data());
        if (surface_.on()) {
            detect_surface_at_tank_walls(P, grid_, kg, mass_, surface_, near_solid_.data());
            apply_surface_stress(P, grid_, kg, mass_, surface_, near_solid_.data());
        }
    });
    reduce_rates();
}

void Simulation2D::reduce_rates() {
    const auto& P = st_.P;
    double a2 = 0.0, u2 = 0.0, rho_max = 0.0;
    bool finite = true;
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static) reduction(max : a2, u2, rho_max) reduction(&& : finite)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] != Kind::Fluid) continue;
        const double ai = norm2(P.a[i]), ui = norm2(P.v[i]);
        finite = finite && std::isfinite(ai) && std::isfinite(ui) && std::isfinite(P.rho[i]);
        a2 = std::max(a2, ai);
        u2 = std::max(u2, ui);
        rho_max = std::max(rho_max, P.rho[i]);
    }
    if (!finite) {
        // A NaN born in a wall or solid particle (its extrapolated pressure, a solid's velocity) reaches the
        // fluid through the rates: which came first cannot be told afterwards, so the fluid particle is named
        // with the first boundary particle that is not finite either.
        std::string also;
        for (std::size_t i = 0; i < P.size() && also.empty(); ++i)
            if (is_boundary(P.kind[i]) && !(std::isfinite(P.p[i]) && std::isfinite(P.rho[i]) && all_finite(P.v[i])))
                also = "; " + std::string(P.kind[i] == Kind::Wall ? "wall" : "solid") + " particle " + std::to_string(P.id[i]) +
                       " has a non-finite " + (!std::isfinite(P.p[i]) ? "pressure" : !std::isfinite(P.rho[i]) ? "density" : "velocity") +
                       " too";
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != Kind::Fluid) continue;
            if (!all_finite(P.a[i])) fail(i, "acceleration", norm(P.a[i]), "not finite" + also);
            if (!all_finite(P.v[i])) fail(i, "velocity", norm(P.v[i]), "not finite" + also);
            if (!std::isfinite(P.rho[i])) fail(i, "density", P.rho[i], "not finite" + also);
        }
    }
    st_.a_max = std::sqrt(a2);
    st_.u_max = std::sqrt(u2);
    st_.rho_max = rho_max;
}

double Simulation2D::stable_dt() {
    if (!st_.rates_fresh) evaluate();
    double c = 0.0;
    if (s_.pressure == PressureModel::Wcsph) c = tait_.sound_speed(std::max(st_.rho_max, s_.rho0));
    if (s_.pressure == PressureModel::Standard) c = standard_.sound_speed(st_.rho_max);
    double a = st_.a_max;
    if (s_.pressure == PressureModel::Pcisph) a = std::max(a, st_.a_max_last);
    // Mueller's Laplacian is scaled on the lattice (laplacian_scale, up to 1.16 at h = dp): the effective
    // viscosity the step must resolve is nu times that.
    const double nu = s_.viscosity == ViscosityModel::Morris   ? s_.nu
                      : s_.viscosity == ViscosityModel::Mueller ? s_.nu * rates_.visc.laplacian_scale
                                                                : 0.0;
    StableStep ss = stable_step(limits_, h_, c, st_.u_max, a, nu);
    // PCISPH has no sound speed in its CFL condition, so at cfl near 1 a particle would move about h per
    // step, beyond the reach of the neighbour lists its prediction uses (step_pcisph). The step aims at
    // pcisph_step_reach of the support, under the pcisph_reach that step_pcisph accepts: the margin is for
    // the part of the motion the step's acceleration adds. (WCSPH and standard SPH steps are bounded far
    // below that by c.)
    if (s_.pressure == PressureModel::Pcisph && st_.u_max > 0.0) {
        const double reach_dt = pcisph_step_reach * support_ / st_.u_max;
        if (reach_dt < ss.dt) ss = {reach_dt, "PCISPH neighbour reach"};
    }
    if (!(ss.dt >= s_.dt_min)) {
        // The particles that set the speed and force limits, found only now: the reduction does not track them.
        const auto& P = st_.P;
        std::size_t fastest = P.size(), hardest = P.size();
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != Kind::Fluid) continue;
            if (fastest == P.size() || norm2(P.v[i]) > norm2(P.v[fastest])) fastest = i;
            if (hardest == P.size() || norm2(P.a[i]) > norm2(P.a[hardest])) hardest = i;
        }
        // PCISPH's |a| may be the last step's with its pressure, which P.a (the non-pressure part) cannot name.
        const bool pressure_from_last = s_.pressure == PressureModel::Pcisph && st_.a_max_last > st_.a_max;
        auto who = [&](std::size_t i) {
            return i == P.size() ? std::string() : " (" + particle_named(i) + ")";
        };
        throw SolverError("diverged", "step " + std::to_string(st_.step + 1) + ", t = " + fmt(st_.t) +
                                          " s: time step = " + fmt(ss.dt) + " s (below the floor dt_min = " +
                                          fmt(s_.dt_min) + " s; limited by " + ss.limited_by + ", largest |u| = " +
                                          fmt(st_.u_max) + " m/s" + who(fastest) + ", largest |a| = " + fmt(a) +
                                          " m/s^2" + (pressure_from_last ? " (the last step's, pressure included)" : who(hardest)) + ")");
    }
    return ss.dt;
}

}  // namespace sphfsi::fluid
