#include "sphfsi/fluid/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include <omp.h>

#include "sphfsi/fluid/continuity.hpp"
#include "sphfsi/fluid/density_summation.hpp"
#include "sphfsi/fluid/kernel_dispatch.hpp"
#include "sphfsi/fluid/lattice.hpp"
#include "sphfsi/fluid/wall_boundary.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {
namespace {

using protocol::SolverError;

std::string fmt(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
}

// c0 from the scene, or 10 u_max with u_max from the scene or sqrt(2 |g| H) (the dam-break front speed
// bound) so density varies by about 1 % (Monaghan 1994).
double sound_speed(const FluidSettings& s) {
    if (s.c0 > 0.0) return s.c0;
    double u = s.u_max;
    if (u <= 0.0) u = std::sqrt(2.0 * s.gravity_magnitude() * s.water_top());
    return 10.0 * u;
}

constexpr std::uint64_t checkpoint_magic = 0x3146495346485053ULL;  // "SPHFSIF1"

}  // namespace

Simulation2D::Simulation2D(const FluidSettings& settings, Scene2D scene, double t0)
    : s_(settings),
      n_fluid_(scene.n_fluid),
      n_wall_(scene.n_wall),
      geometry_(scene.geometry),
      h_(settings.h()),
      support_(support_radius(settings.kernel, settings.h())),
      mass_(settings.rho0 * settings.dp * settings.dp),
      c0_(settings.pressure == PressureModel::Standard ? std::sqrt(settings.k) : sound_speed(settings)),
      tait_(sound_speed(settings) > 0 ? sound_speed(settings) : 1.0, settings.rho0, settings.gamma, settings.background),
      standard_(settings.k, settings.rho0, settings.background),
      domain_lo_(scene.domain_lo),
      domain_hi_(scene.domain_hi) {
    st_.P = std::move(scene.particles);
    // Threads: the scene's count, or all the process may use. Below a few thousand particles a step takes
    // tens of microseconds, and the synchronisation of its ~8 parallel loops costs more than a second
    // thread gains (and far more when the cores are shared and a thread gets descheduled at a barrier).
    threads_ = s_.threads > 0 ? s_.threads : omp_get_max_threads();
    if (st_.P.size() < small_problem) threads_ = 1;
    omp_set_num_threads(threads_);
    st_.t = t0;
    first_solid_id_ = static_cast<std::int32_t>(st_.P.size());

    // Initial densities: hydrostatic for integrated densities under gravity (so the column starts in
    // equilibrium instead of ringing), rho0 otherwise: summed densities follow from the positions, and a
    // Shepard-normalised density remembers its start value in a particle that flies off alone (a
    // hydrostatic start would leave such a particle pressurised, skating away from the floor).
    auto& P = st_.P;
    const double g_down = -s_.gravity[1];
    for (std::size_t i = 0; i < P.size(); ++i) {
        P.rho[i] = s_.rho0;
        if (i < n_fluid_ && s_.density == DensityMethod::Continuity && g_down > 0.0) {
            const double p = s_.rho0 * g_down * (scene.column_top[i] - P.x[i][1]) + s_.background;
            P.rho[i] = s_.pressure == PressureModel::Wcsph ? tait_.density(p) : standard_.density(p);
        }
    }

    // Kernel sums of density (summation, Shepard's volumes, PCISPH's prediction, the kinematic floor) weigh
    // each neighbour with m_sum = rho0 / sum_j W_ij over the initial lattice instead of the particle mass
    // m = rho0 dp^Dim. On a lattice the sum of dp^Dim W_ij is not 1 but a quadrature of the kernel's
    // integral: 1.0051 for the default Wendland kernel at h = 1.5 dp, 1.0034 for the cubic spline (1.0012
    // and 1.0000 at h = 2 dp). With m, water resting on its initial lattice summed to 1.005 rho0, which the
    // equation of state read as compression: standard SPH at the thesis's k = 1000 m^2/s^2 started every
    // scene with 5.1 kPa in its bulk (the dam-break column's bottom pressure is 2.0 kPa), WCSPH on summed
    // densities with 2.0 kPa, and PCISPH with half of its eta = 1 % spent (eta = 0.1 % could not be met at
    // all). Measured effects: docs/validation.md, "Summed densities on the initial lattice". Forces, energies
    // and the continuity equation keep m, so the water weighs what its volume does.
    summation_mass_ = s_.rho0 / with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto&) {
        double sum = kw.w(0.0);
        for_each_lattice_neighbour<Dim>(s_.dp, support_, [&](const V&, double r) { sum += kw.w(r); });
        return sum;
    });

    const double eta2 = 0.01 * h_ * h_;
    rates_.mass = mass_;
    rates_.visc = ViscosityParams{s_.viscosity, s_.alpha, c0_, s_.nu, h_, eta2, 0.001 * h_ * h_};
    rates_.viscous_walls = s_.no_slip;
    // The fused rate pass computes drho/dt only for the predictor-corrector (which evaluates every rate at
    // the same state); the symplectic schemes advance density from the kicked velocities (continuity.hpp).
    continuity_ = s_.density == DensityMethod::Continuity;
    // Kinematic density floor. An integrated density should track the particle's kernel sum rho_sum =
    // m sum_j W_ij over fluid, wall and solid neighbours (they differ by the offset of the initial state, about
    // zero). With negative pressures clamped, rarefied fluid feels no restoring force, and through violent
    // splashes the first-order integration loses that tracking: in elastic_obstacle.toml at dp = 2 mm the
    // returning wave flows at 0.4 to 0.9 rho0 with full neighbourhoods, and a particle thrown off the
    // cantilever then fell to 0.009 rho0 ("diverged" at t = 0.65 s). So at each evaluation the density is
    // raised to the kinematic density (the kernel sum with m_sum, rho0 on the initial lattice), but
    // never above rho(p = 0): a particle can be as rarefied as its positions say, not more. This cannot create
    // pressure (compressed states are untouched) and leaves free-surface particles alone (their kernel sum is
    // truncated, below their density); a lone particle keeps at least m W(0), about a quarter of rho0.
    // The rate pass takes the kernel sums and the density is raised after it (interaction.hpp: below
    // rho(p = 0) the pressure is zero either way, so the pass sees the pressures a prior raise would give).
    kinematic_floor_ = continuity_ && s_.clamp_negative && s_.pressure != PressureModel::Pcisph;
    if (kinematic_floor_)
        kinematic_cap_ = s_.pressure == PressureModel::Wcsph ? tait_.density(0.0) : standard_.density(0.0);
    rates_.continuity = continuity_ && s_.integrator == Integrator::PredictorCorrector;
    rates_.wall_continuity = rates_.continuity && s_.wall == WallModel::Dummy;
    rates_.diffusion.model = s_.diffusion;
    rates_.diffusion.coef = s_.delta * h_ * c0_;
    if (s_.diffusion == DensityDiffusion::Fourtakas)
        rates_.diffusion.hydro = V{{s_.rho0 * s_.gravity[0] / (c0_ * c0_), s_.rho0 * s_.gravity[1] / (c0_ * c0_)}};
    // Monaghan's (1994) wall force (boundary.repulsive). Pressure alone does not keep spray out of a wall: the
    // continuity equation reads a jet breaking up as expansion, so a spray particle flies at a fraction of rho0
    // (0.48 rho0 in elastic_obstacle.toml at dp = 4 mm) and, with negative pressures clamped, at p = 0; the Adami
    // wall pressure is extrapolated from the fluid, so it is zero too (plus a hydrostatic head of a few pascals),
    // and the particle meets no resistance until its density has climbed back to rho0 by the wall's own terms in
    // the continuity equation, i.e. until it is deep inside the wall layers or through them. The force acts only
    // within r0 = dp of a wall or solid particle, closer than fluid rests against a wall (about dp from the first
    // layer), so it leaves resting fluid alone and barely touches fluid pressed along a wall (hydrostatic bottom
    // pressure and dam-break front change by less than 0.5 % of their values), and it stops a particle before
    // its centre reaches the wall surface (tests/fluid/test_scene.cpp, the spray case).
    rates_.repulsive = s_.repulsive;
    rates_.repulsive_r0 = s_.dp;
    rates_.repulsive_d = s_.repulsive_d > 0.0 ? s_.repulsive_d : 5.0 * s_.gravity_magnitude() * s_.water_top();
    rates_.gravity = V{{s_.gravity[0], s_.gravity[1]}};
    surface_ = make_surface_stress<Dim>(V{{s_.wind_shear[0], s_.wind_shear[1]}}, s_.surface_threshold, h_, s_.dp);

    pcisph_.mass = mass_;
    pcisph_.summation_mass = summation_mass_;
    pcisph_.rho0 = s_.rho0;
    pcisph_.eta = s_.eta;
    pcisph_.min_iterations = s_.min_iterations;
    pcisph_.max_iterations = s_.max_iterations;
    pcisph_.clamp_negative = s_.clamp_negative;
    pcisph_.dummy_boundaries = s_.wall == WallModel::Dummy;
    pcisph_.delta_dt2 = with_kernels<Dim>(s_.kernel, h_, [&](const auto&, const auto& kg) {
        return pcisph_delta_dt2<Dim>(kg, s_.dp, mass_, summation_mass_, s_.rho0);
    });

    limits_ = StepLimits{s_.cfl, s_.force_factor, s_.viscous_factor, s_.dt_max};
    if (!s_.step_log.empty()) {
        step_log_ = std::make_unique<std::ofstream>(s_.step_log, std::ios::app);
        if (!*step_log_) throw SolverError("bad_config", "cannot open step_log file '" + s_.step_log + "'");
        *step_log_ << "step,t,dt,iterations,max_density_error\n";
    }
    grid_.configure(domain_lo_, domain_hi_, support_, s_.periodic);
}

void Simulation2D::add_solids(const std::vector<V>& reference, SolidKinematics kinematics,
                              const std::function<bool(const V&)>& inside_solid) {
    auto& P = st_.P;
    // Drop fluid particles that overlap the solid; ids are renumbered so they stay 0..n-1.
    ParticleStore<Dim> kept;
    const double min_d2 = 0.75 * s_.dp * 0.75 * s_.dp;
    for (std::size_t i = 0; i < P.size(); ++i) {
        bool drop = false;
        if (P.kind[i] == Kind::Fluid) {
            drop = inside_solid(P.x[i]);
            for (std::size_t k = 0; !drop && k < reference.size(); ++k) drop = norm2(P.x[i] - reference[k]) < min_d2;
        }
        if (drop) continue;
        kept.x.push_back(P.x[i]);
        kept.v.push_back(P.v[i]);
        kept.rho.push_back(P.rho[i]);
        kept.tag.push_back(P.tag[i]);
        kept.kind.push_back(P.kind[i]);
    }
    n_fluid_ = static_cast<std::size_t>(std::count(kept.kind.begin(), kept.kind.end(), Kind::Fluid));
    first_solid_id_ = static_cast<std::int32_t>(kept.x.size());
    for (const V& x : reference) {
        kept.x.push_back(x);
        kept.v.push_back(V{});
        kept.rho.push_back(s_.rho0);
        kept.tag.push_back(-2);
        kept.kind.push_back(Kind::Solid);
    }
    kept.id.resize(kept.x.size());
    for (std::size_t i = 0; i < kept.id.size(); ++i) kept.id[i] = static_cast<std::int32_t>(i);
    kept.resize(kept.x.size());
    P = std::move(kept);
    n_solid_ = reference.size();
    solid_acc_.assign(n_solid_, V{});
    st_.solid_force_sum.assign(n_solid_, V{});
    kinematics_ = std::move(kinematics);
    // The grid must cover the solid too.
    for (const V& x : reference)
        for (int k = 0; k < Dim; ++k)
            if (!s_.periodic[static_cast<std::size_t>(k)]) {
                domain_lo_[k] = std::min(domain_lo_[k], x[k] - support_);
                domain_hi_[k] = std::max(domain_hi_[k], x[k] + support_);
            }
    grid_.configure(domain_lo_, domain_hi_, support_, s_.periodic);
    st_.rates_fresh = false;
}

// ---------------------------------------------------------------------------------------------------
// Evaluation of rates at the current state.

void Simulation2D::wrap_periodic() {
    auto& P = st_.P;
    for (int k = 0; k < Dim; ++k) {
        if (!s_.periodic[static_cast<std::size_t>(k)]) continue;
        const double lo = domain_lo_[k], len = domain_hi_[k] - domain_lo_[k];
        const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
        for (long long q = 0; q < n; ++q) {
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

void Simulation2D::evaluate() {
    auto& P = st_.P;
    move_solids(st_.t);
    sort_particles();
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    const bool pcisph = s_.pressure == PressureModel::Pcisph;
    const bool dummy = s_.wall == WallModel::Dummy;
    const bool summation = s_.density != DensityMethod::Continuity;
    with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto& kg) {
        if (summation) {
            // Written in place: a particle's sum reads no density but its own (a boundary particle keeps it).
            const std::vector<double>* volumes = nullptr;
            if (s_.density == DensityMethod::Shepard) {
                summation_density(P, grid_, kw, summation_mass_, true, nullptr, rho_scratch_);  // plain sums: the volumes
                volumes = &rho_scratch_;
            }
            summation_density(P, grid_, kw, summation_mass_, dummy, volumes, P.rho);
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
                // A boundary particle never pulls fluid onto the wall; fluid may be clamped by choice.
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
        if (surface_.on()) apply_surface_stress(P, grid_, kg, mass_, surface_);
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

double Simulation2D::boundary_density(double p) const {
    if (s_.pressure == PressureModel::Pcisph) return s_.rho0;
    return s_.pressure == PressureModel::Wcsph ? tait_.density(p) : standard_.density(p);
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
        if (s_.kernel_correction) {
            // The solids' new densities change the matrices L of their fluid neighbours, and the pair terms
            // (L_i + L_j)/2 of those neighbours' own neighbours with them: mark that second ring too.
            mark_fluid_neighbours([&](std::uint32_t i) { return near_solid_[i] == 1 && P.kind[i] == Kind::Fluid; }, 2);
            update_correction(kg);
        }
        // The factors of all particles: the buffer is scratch (the sort reuses it), not state.
        compute_rates(P, grid_, kw, kg, ViscosityKernel<Dim>(h_), fill_rate_factors(), rates_, nullptr,
                      near_solid_.data());
        if (surface_.on()) apply_surface_stress(P, grid_, kg, mass_, surface_, near_solid_.data());
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
        for (std::size_t i = 0; i < P.size(); ++i) {
            if (P.kind[i] != Kind::Fluid) continue;
            if (!all_finite(P.a[i])) fail(i, "acceleration", norm(P.a[i]), "not finite");
            if (!all_finite(P.v[i])) fail(i, "velocity", norm(P.v[i]), "not finite");
            if (!std::isfinite(P.rho[i])) fail(i, "density", P.rho[i], "not finite");
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
    const double nu = (s_.viscosity == ViscosityModel::Morris || s_.viscosity == ViscosityModel::Mueller) ? s_.nu : 0.0;
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
        step_dt_ = ss.dt;
        throw SolverError("diverged", "step " + std::to_string(st_.step + 1) + ", t = " + fmt(st_.t) +
                                          " s: time step = " + fmt(ss.dt) + " s (below the floor dt_min = " +
                                          fmt(s_.dt_min) + " s; limited by " + ss.limited_by + ", largest |u| = " +
                                          fmt(st_.u_max) + " m/s, largest |a| = " + fmt(a) + " m/s^2)");
    }
    return ss.dt;
}

// ---------------------------------------------------------------------------------------------------
// Time stepping.

void Simulation2D::accumulate_solid_forces(double weight) {
    if (n_solid_ == 0) return;
    const auto& P = st_.P;
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Solid)
            st_.solid_force_sum[static_cast<std::size_t>(P.id[i] - first_solid_id_)] += P.a[i] * (mass_ * weight);
    st_.solid_weight += weight;
}

std::vector<Simulation2D::V> Simulation2D::mean_solid_forces() const {
    std::vector<V> f(n_solid_);
    const double inv = st_.solid_weight > 0.0 ? 1.0 / st_.solid_weight : 0.0;
    for (std::size_t k = 0; k < n_solid_; ++k) f[k] = st_.solid_force_sum[k] * inv;
    return f;
}

void Simulation2D::density_rates() {
    const auto& P = st_.P;
    const long long n = static_cast<long long>(P.size());
    rho_scratch_.resize(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) rho_scratch_[static_cast<std::size_t>(q)] = 1.0 / P.rho[static_cast<std::size_t>(q)];
    with_kernels<Dim>(s_.kernel, h_, [&](const auto&, const auto& kg) {
        continuity_rates(st_.P, grid_, kg, mass_, s_.wall == WallModel::Dummy, rates_.diffusion, rho_scratch_.data());
    });
}

void Simulation2D::step_symplectic(double dt) {
    // Semi-implicit Euler (the thesis): v^{n+1} = v^n + dt a^n, then the position-like variables from the
    // new velocities: x^{n+1} = x^n + dt v^{n+1}, rho^{n+1} = rho^n + dt drho(x^n, v^{n+1}).
    auto& P = st_.P;
    accumulate_solid_forces(dt);
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid) P.v[i] += P.a[i] * dt;
    }
    drift(dt);
    st_.t += dt;
    st_.rates_fresh = false;
}

void Simulation2D::drift(double dt) {
    // Positions, and integrated densities from the current velocities (grid still matches the positions).
    auto& P = st_.P;
    if (continuity_) density_rates();
    const bool cont = continuity_, wall_cont = continuity_ && s_.wall == WallModel::Dummy;
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid) {
            P.x[i] += P.v[i] * dt;
            if (cont) P.rho[i] += P.drho[i] * dt;
        } else if (wall_cont && is_boundary(P.kind[i])) {
            P.rho[i] += P.drho[i] * dt;
        }
    }
}

void Simulation2D::step_verlet(double dt) {
    // Velocity Verlet (kick-drift-kick) with density drifting like position: the rates of the previous
    // evaluation start the step, one force evaluation per step at the new positions and densities.
    auto& P = st_.P;
    const double half = 0.5 * dt;
    const long long n = static_cast<long long>(P.size());
    auto kick = [&] {
#pragma omp parallel for schedule(static)
        for (long long q = 0; q < n; ++q) {
            const std::size_t i = static_cast<std::size_t>(q);
            if (P.kind[i] == Kind::Fluid) P.v[i] += P.a[i] * half;
        }
    };
    accumulate_solid_forces(half);
    kick();
    drift(dt);
    st_.t += dt;
    evaluate();
    accumulate_solid_forces(half);
    kick();
    st_.rates_fresh = true;  // a^{n+1} at (x^{n+1}, rho^{n+1}, v^{n+1/2}) starts the next step
}

void Simulation2D::step_predictor_corrector(double dt) {
    // Monaghan (1989): predict to the half step, evaluate there, then
    // v^{n+1} = v^n + dt a^{n+1/2}, x^{n+1} = x^n + dt (v^n + dt/2 a^{n+1/2}), rho likewise.
    auto& P = st_.P;
    const bool cont = rates_.continuity, wall_cont = rates_.wall_continuity;
    const double half = 0.5 * dt;
    const long long n = static_cast<long long>(P.size());
    P.x_start.resize(P.size());
    P.v_start.resize(P.size());
    P.rho_start.resize(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        P.x_start[i] = P.x[i];
        P.v_start[i] = P.v[i];
        P.rho_start[i] = P.rho[i];
        if (P.kind[i] == Kind::Fluid) {
            P.x[i] += P.v[i] * half;
            P.v[i] += P.a[i] * half;
            if (cont) P.rho[i] += P.drho[i] * half;
        } else if (wall_cont && is_boundary(P.kind[i])) {
            P.rho[i] += P.drho[i] * half;
        }
    }
    const double t0 = st_.t;
    st_.t = t0 + half;
    evaluate();  // may reorder: the *_start arrays travel with the particles
    accumulate_solid_forces(dt);
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid) {
            P.x[i] = P.x_start[i] + (P.v_start[i] + P.a[i] * half) * dt;
            P.v[i] = P.v_start[i] + P.a[i] * dt;
            if (cont) P.rho[i] = P.rho_start[i] + P.drho[i] * dt;
        } else if (wall_cont && is_boundary(P.kind[i])) {
            P.rho[i] = P.rho_start[i] + P.drho[i] * dt;
        }
    }
    st_.t = t0 + dt;
    st_.rates_fresh = false;
}

double Simulation2D::max_predicted_displacement() const {
    const auto& P = st_.P;
    const long long nn = static_cast<long long>(P.size());
    double d2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : d2)
    for (long long q = 0; q < nn; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid) d2 = std::max(d2, norm2(pci_.x_pred[i] - P.x[i]));
    }
    return std::sqrt(d2);
}

double Simulation2D::step_pcisph(double dt, bool adaptive, WindowStats& ws) {
    auto& P = st_.P;
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    pci_.resize(n);
    // Boundary particles' end-of-step positions: walls stay, solids go to t + dt.
    while (true) {
        const double t_end = st_.t + dt;
#pragma omp parallel for schedule(static)
        for (long long q = 0; q < nn; ++q) {
            const std::size_t i = static_cast<std::size_t>(q);
            if (P.kind[i] == Kind::Wall || P.kind[i] == Kind::Escaped) pci_.x_pred[i] = P.x[i];
            if (P.kind[i] == Kind::Solid && kinematics_) {
                V v, a;
                const std::size_t k = static_cast<std::size_t>(P.id[i] - first_solid_id_);
                kinematics_(k, t_end, pci_.x_pred[i], v, a);
            }
        }
        const PcisphOutcome out = with_kernels<Dim>(s_.kernel, h_, [&](const auto& kw, const auto& kg) {
            return pcisph_solve(P, grid_, kw, kg, pcisph_, dt, pci_, [&] {
                extrapolate_boundary_state(P, grid_, kw, rates_.gravity, true, [&](double) { return s_.rho0; },
                                           [&](std::uint32_t w) { return boundary_acceleration(w); });
            });
        });
        // The prediction searches the neighbour lists of time t; a particle predicted to move further than a
        // quarter of the kernel support misses neighbours it reaches during the step (a wall ahead of it, at
        // an impact), its predicted density comes out low and it is driven into the wall: the failure mode
        // the PCISPH stability sweep found at cfl = 1 (docs/validation.md). Such a step is halved like one
        // that did not converge.
        const double moved = out.converged ? max_predicted_displacement() : 0.0;
        if (out.converged && moved <= pcisph_reach * support_) {
            ws.iterations += static_cast<std::uint64_t>(out.iterations);
            ws.max_iterations = std::max(ws.max_iterations, out.iterations);
            ws.max_density_error = std::max(ws.max_density_error, out.max_density_error);
            break;
        }
        if (!adaptive && out.converged)
            throw SolverError("not_converged", "step " + std::to_string(st_.step + 1) + ", t = " + fmt(st_.t) +
                                                   " s: PCISPH predicts a particle moving " + fmt(moved) +
                                                   " m in the fixed step " + fmt(dt) + " s, beyond the " +
                                                   fmt(pcisph_reach * support_) + " m (" + fmt(pcisph_reach) +
                                                   " of the kernel support) that its neighbour lists reach");
        if (!adaptive)
            throw SolverError("not_converged", "step " + std::to_string(st_.step + 1) + ", t = " + fmt(st_.t) +
                                                   " s: PCISPH density error " + fmt(out.max_density_error) +
                                                   " of rho0 after " + std::to_string(out.iterations) +
                                                   " corrections (eta = " + fmt(s_.eta) + ") with the fixed step " +
                                                   fmt(dt) + " s");
        // Retry with half the step (P.a still holds the non-pressure accelerations).
        dt *= 0.5;
        ++ws.retries;
        if (dt < s_.dt_min)
            throw SolverError("diverged", "step " + std::to_string(st_.step + 1) + ", t = " + fmt(st_.t) +
                                              " s: time step = " + fmt(dt) + " s (below the floor dt_min = " +
                                              fmt(s_.dt_min) + " s; PCISPH did not converge, density error " +
                                              fmt(out.max_density_error) + " of rho0)");
    }
    double a2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : a2)
    for (long long q = 0; q < nn; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (!(P.kind[i] == Kind::Fluid || P.kind[i] == Kind::Solid)) continue;
        P.a[i] += pci_.a_p[i];
        if (P.kind[i] == Kind::Fluid) {
            P.v[i] += P.a[i] * dt;
            P.x[i] += P.v[i] * dt;
            P.rho[i] = pci_.rho_pred[i];
            a2 = std::max(a2, norm2(P.a[i]));
        }
    }
    st_.a_max_last = std::sqrt(a2);
    accumulate_solid_forces(dt);
    st_.t += dt;
    st_.rates_fresh = false;
    return dt;
}

double Simulation2D::take_step(double dt, bool adaptive, WindowStats& ws) {
    step_dt_ = dt;
    switch (s_.pressure == PressureModel::Pcisph ? Integrator::SymplecticEuler : s_.integrator) {
        case Integrator::SymplecticEuler:
            if (s_.pressure == PressureModel::Pcisph)
                dt = step_pcisph(dt, adaptive, ws);
            else
                step_symplectic(dt);
            break;
        case Integrator::VelocityVerlet: step_verlet(dt); break;
        case Integrator::PredictorCorrector: step_predictor_corrector(dt); break;
    }
    ++st_.step;
    const double rho_max = check_state();
    if (s_.pressure != PressureModel::Pcisph)
        ws.max_density_error = std::max(ws.max_density_error, (std::max(rho_max, st_.rho_max) - s_.rho0) / s_.rho0);
    return dt;
}

WindowStats Simulation2D::advance(double t_end, std::uint32_t substeps, const std::function<void()>& on_step) {
    WindowStats ws;
    ws.dt_min = std::numeric_limits<double>::infinity();
    st_.solid_force_sum.assign(n_solid_, V{});
    st_.solid_weight = 0.0;
    refresh_solid_rates();  // the window's wall acceleration into rates kept from the last window's end
    const double t_start = st_.t;
    auto record = [&](double dt) {
        ++ws.steps;
        ws.dt_min = std::min(ws.dt_min, dt);
        ws.dt_max = std::max(ws.dt_max, dt);
        ws.dt_last = dt;
        if (step_log_)
            *step_log_ << st_.step << ',' << st_.t << ',' << dt << ',' << ws.iterations << ',' << ws.max_density_error << '\n';
        if (on_step) on_step();
    };
    if (substeps > 0) {
        const double dt = (t_end - t_start) / substeps;
        for (std::uint32_t k = 0; k < substeps; ++k) {
            if (!st_.rates_fresh) evaluate();
            const double taken = take_step(dt, false, ws);
            if (k + 1 == substeps) st_.t = t_end;  // no drift from summing dt
            record(taken);
        }
    } else {
        while (st_.t < t_end) {
            // Land exactly on t_end in equal steps: the rest of the window in the fewest steps no longer
            // than the stable step, so no step is much shorter than the one before it (at least about half
            // of it). A clipped sliver would do harm with PCISPH, whose pressure is what corrects the
            // predicted density error within one step, p ~ 1/dt^2: a last step of 2 % of the stable one
            // gave pressures 30 times hydrostatic in the record and kicked the particles with velocity
            // (docs/validation.md, "PCISPH's pressure and the step").
            const double remaining = t_end - st_.t;
            const double steps_left = std::max(1.0, std::ceil(remaining / stable_dt() * (1.0 - 1e-12)));
            const bool last = steps_left == 1.0;
            const double dt = remaining / steps_left;  // exactly `remaining` when last
            const double taken = take_step(dt, true, ws);
            if (last && taken == dt) st_.t = t_end;
            record(taken);
        }
    }
    if (ws.steps == 0) ws.dt_min = 0.0;
    if (step_log_) step_log_->flush();  // a window's lines are on disk when its reply goes out
    return ws;
}

// ---------------------------------------------------------------------------------------------------
// Failure checks.

void Simulation2D::fail(std::size_t i, const std::string& quantity, double value, const std::string& why) const {
    throw SolverError("diverged", "step " + std::to_string(st_.step) + ", t = " + fmt(st_.t) + " s: particle " +
                                      std::to_string(st_.P.id[i]) + ": " + quantity + " = " + fmt(value) + " (" + why + ")");
}

// Over the top of a side wall of an open tank and out beyond its outer face: the particle has left the tank
// (a splash, or water spilling over the brim), which is physics, not a failure. "Over the top" allows the
// centre to be up to the wall's thickness below the wall's top when it passes the outer face: water spilling
// slowly over a brim rides the top with its centre at about the top surface and drops as soon as it rounds the
// outer corner (the brim-full tank of tests/fluid/test_failure.cpp put a spilling particle's centre 0.13 mm
// below the top at dp = 2.5 mm, and that used to stop the run as "lost through the wall"; so did a brim-full
// wind-driven basin). A particle that went through the wall lower down is still a failure (check_state).
bool Simulation2D::over_the_wall(const V& x) const {
    const auto& g = geometry_;
    return g.walls_x && !g.lid && x[1] > g.height - g.thickness && (x[0] < -g.thickness || x[0] > g.width + g.thickness);
}

void Simulation2D::mark_escaped() {
    // Escaped particles are frozen and leave the computation.
    const auto& g = geometry_;
    if (!g.walls_x || g.lid) return;
    auto& P = st_.P;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        if (over_the_wall(P.x[i])) {
            P.kind[i] = Kind::Escaped;
            P.v[i] = V{};
            P.a[i] = V{};
            P.drho[i] = 0.0;
            ++st_.escaped;
        }
    }
}

double Simulation2D::check_state() {
    mark_escaped();
    const auto& P = st_.P;
    const auto& g = geometry_;
    const double lo = s_.min_density_ratio * s_.rho0, hi = s_.max_density_ratio * s_.rho0;
    const double v_cap = s_.max_mach * c0_;  // 0: no reference speed (PCISPH without gravity or u_max)
    bool bad = false;
    double rho_max = 0.0;
    const long long n = static_cast<long long>(P.size());
    auto broken = [&](std::size_t i) {
        const V& x = P.x[i];
        if (!all_finite(x) || !all_finite(P.v[i]) || !std::isfinite(P.rho[i])) return true;
        if (P.rho[i] < lo || P.rho[i] > hi) return true;
        if (v_cap > 0.0 && dot(P.v[i], P.v[i]) > v_cap * v_cap) return true;
        // mark_escaped has taken every particle that left over a side wall; beyond one now is through it.
        if (g.walls_x && (x[0] < -g.thickness || x[0] > g.width + g.thickness)) return true;
        if (g.floor && x[1] < -g.thickness) return true;
        if (g.lid && x[1] > g.height + g.thickness) return true;
        for (const Box& b : g.obstacles) {
            const double d = std::min(g.thickness, 0.5 * std::min(b.width, b.height));
            if (x[0] > b.x0 + d && x[0] < b.x0 + b.width - d && x[1] > b.y0 + d && x[1] < b.y0 + b.height - d) return true;
        }
        return false;
    };
#pragma omp parallel for schedule(static) reduction(|| : bad) reduction(max : rho_max)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] != Kind::Fluid) continue;
        bad = bad || broken(i);
        rho_max = std::max(rho_max, P.rho[i]);
    }
    if (!bad) return rho_max;
    // Name the first offender (lowest id), with the quantity and why.
    std::size_t worst = P.size();
    for (std::size_t i = 0; i < P.size(); ++i)
        if (P.kind[i] == Kind::Fluid && broken(i) && (worst == P.size() || P.id[i] < P.id[worst])) worst = i;
    const std::size_t i = worst;
    const V& x = P.x[i];
    if (!all_finite(x)) fail(i, "position", std::isfinite(x[0]) ? x[1] : x[0], "not finite");
    if (!all_finite(P.v[i])) fail(i, "velocity", norm(P.v[i]), "not finite");
    if (!std::isfinite(P.rho[i])) fail(i, "density", P.rho[i], "not finite");
    if (P.rho[i] < lo) fail(i, "density", P.rho[i], "below min_density_ratio * rho0 = " + fmt(lo) + " kg/m^3");
    if (P.rho[i] > hi) fail(i, "density", P.rho[i], "above max_density_ratio * rho0 = " + fmt(hi) + " kg/m^3");
    if (v_cap > 0.0 && dot(P.v[i], P.v[i]) > v_cap * v_cap)
        fail(i, "speed", norm(P.v[i]), "above max_mach * c0 = " + fmt(v_cap) + " m/s, at (" + fmt(x[0]) + ", " + fmt(x[1]) + ") m");
    if (g.walls_x && x[0] < -g.thickness) fail(i, "x", x[0], "beyond the outer face of the left wall at x = " + fmt(-g.thickness) + " m, at y = " + fmt(x[1]) + " m: lost through the wall");
    if (g.walls_x && x[0] > g.width + g.thickness) fail(i, "x", x[0], "beyond the outer face of the right wall at x = " + fmt(g.width + g.thickness) + " m, at y = " + fmt(x[1]) + " m: lost through the wall");
    if (g.floor && x[1] < -g.thickness) fail(i, "y", x[1], "below the outer face of the floor at y = " + fmt(-g.thickness) + " m: lost through the wall");
    if (g.lid && x[1] > g.height + g.thickness) fail(i, "y", x[1], "above the outer face of the lid at y = " + fmt(g.height + g.thickness) + " m: lost through the wall");
    fail(i, "position", x[0], "inside an obstacle, deeper than its wall layers: lost through the wall (y = " + fmt(x[1]) + " m)");
}

Simulation2D::Crossing Simulation2D::wall_crossings() const {
    // A centre within 0.1 dp of a wall surface is on it, not through it: SPH puts the surface half a spacing
    // from the first wall layer, and a particle sliding round a convex corner grazes it.
    Crossing c;
    const auto& P = st_.P;
    const auto& g = geometry_;
    const double tol = 0.1 * s_.dp;
    for (std::size_t i = 0; i < P.size(); ++i) {
        if (P.kind[i] != Kind::Fluid) continue;
        const V& x = P.x[i];
        const bool beside_walls = g.lid || x[1] <= g.height;
        std::string why;
        if (g.walls_x && beside_walls && x[0] < -tol) why = "left of the left wall surface";
        else if (g.walls_x && beside_walls && x[0] > g.width + tol) why = "right of the right wall surface";
        else if (g.floor && x[1] < -tol) why = "below the floor surface";
        else if (g.lid && x[1] > g.height + tol) why = "above the lid surface";
        for (const Box& b : g.obstacles)
            if (why.empty() && x[0] > b.x0 + tol && x[0] < b.x0 + b.width - tol && x[1] > b.y0 + tol &&
                x[1] < b.y0 + b.height - tol)
                why = "inside an obstacle";
        if (why.empty()) continue;
        if (c.count++ == 0)
            c.first = "particle " + std::to_string(P.id[i]) + " at (" + fmt(x[0]) + ", " + fmt(x[1]) + ") m: " + why;
    }
    return c;
}

// ---------------------------------------------------------------------------------------------------
// State.

std::size_t Simulation2D::free_surface_count() const {
    const auto& P = st_.P;
    const float threshold = static_cast<float>(s_.surface_threshold);
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
           pci_.memory_bytes() + correction_.capacity() * sizeof(Mat<Dim>);
}

void Simulation2D::save() {
    saved_ = st_;
    has_saved_ = true;
}

void Simulation2D::restore() {
    if (!has_saved_) throw SolverError("bad_state", "RESTORE before any SAVE");
    st_ = saved_;
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
}

void Simulation2D::read_state(ByteReader& r) {
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
    st_.rates_fresh = r.get<std::uint8_t>() != 0;
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
    sort_particles();  // rebuild the grid for the restored positions (already in cell order: no reordering)
}

}  // namespace sphfsi::fluid
