// Simulation2D, construction: the models' parameters from the settings, the initial densities and the
// solid particles. The rest of the class: simulation_rates.cpp (rates at the current state),
// simulation_stepping.cpp (integrators and the window loop), simulation_checks.cpp (failure checks),
// simulation_state.cpp (diagnostics, save/restore, checkpoints).
#include "sphfsi/fluid/simulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <omp.h>

#include "sphfsi/fluid/kernel_dispatch.hpp"
#include "sphfsi/fluid/lattice.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {
namespace {

using protocol::SolverError;

// c0 from the scene, or 10 u_max with u_max from the scene or sqrt(2 |g| H) (the dam-break front speed
// bound) so density varies by about 1 % (Monaghan 1994).
double sound_speed(const FluidSettings& s) {
    if (s.c0 > 0.0) return s.c0;
    double u = s.u_max;
    if (u <= 0.0) u = std::sqrt(2.0 * s.gravity_magnitude() * s.water_top());
    return 10.0 * u;
}

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

    correction_min_divergence_ = static_cast<float>(full_support_divergence<Dim>(
        with_kernels<Dim>(s_.kernel, h_, [&](const auto&, const auto& kg) { return lattice_divergence<Dim>(kg, s_.dp); })));

    const double eta2 = 0.01 * h_ * h_;
    rates_.mass = mass_;
    rates_.visc = ViscosityParams{s_.viscosity, s_.alpha, c0_, s_.nu, h_, eta2, 0.001 * h_ * h_};
    // Mueller's Laplacian estimate sum_j V_j (v_j - v_i) lap W_ij is consistent when sum_j V_j r_ij^2 lap W_ij
    // = 2 Dim, which its constant gives in the continuum but not on a lattice of the fluid's spacing: 3.811 at
    // h = 1.5 dp (-4.7 %), 4.29 at 1.3 dp, 3.94 at 2 dp in 2D. Uncorrected, Poiseuille flow came out 7.0 %
    // (L2) from the series solution at h = 1.5 dp (a review). So the constant is normalised on the initial
    // lattice, as the summation mass is above.
    if (s_.viscosity == ViscosityModel::Mueller) {
        const ViscosityKernel<Dim> vk(h_);
        double sum = 0.0;
        for_each_lattice_neighbour<Dim>(s_.dp, vk.support(), [&](const V&, double r) { sum += r * r * vk.laplacian(r); });
        rates_.visc.laplacian_scale = 2.0 * Dim / (sum * std::pow(s_.dp, Dim));
    }
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
    std::vector<WallPlane> wall_planes;  // the tank's wall surfaces: where the free surface ends, what its detection mirrors
    if (geometry_.walls_x) wall_planes.insert(wall_planes.end(), {{0, 0.0, 1}, {0, geometry_.width, -1}});
    if (geometry_.floor) wall_planes.push_back({1, 0.0, 1});
    if (geometry_.lid) wall_planes.push_back({1, geometry_.height, -1});
    surface_ = make_surface_stress<Dim>(V{{s_.wind_shear[0], s_.wind_shear[1]}}, surface_threshold(), h_, s_.dp,
                                        std::move(wall_planes));

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
        step_log_->precision(17);  // t must tell steps of 1e-5 s apart at t = 10 s and more
        *step_log_ << "step,t,dt,iterations,max_density_error\n" << std::flush;
        // A file that opens but takes no bytes (/dev/full, a full disk) is found here, before the first step.
        if (!*step_log_) throw SolverError("bad_config", "cannot write step_log file '" + s_.step_log + "'");
    }
    grid_.configure(domain_lo_, domain_hi_, support_, s_.periodic);
}

void Simulation2D::add_solids(const std::vector<V>& reference, const std::vector<V>& at_start, SolidKinematics kinematics,
                              const std::function<bool(const V&)>& inside_solid) {
    auto& P = st_.P;
    // Drop fluid particles that overlap the solid; ids are renumbered so they stay 0..n-1.
    ParticleStore<Dim> kept;
    const double min_d = 0.75 * s_.dp;
    // The solid particles binned on cells min_d wide, sorted by cell: a fluid particle looks at the 3^Dim
    // cells around its own (every fluid particle against every solid one was O(N_f N_s)).
    using Cell = std::array<long long, Dim>;
    auto cell_of = [min_d](const V& x) {
        Cell c;
        for (int k = 0; k < Dim; ++k) c[static_cast<std::size_t>(k)] = static_cast<long long>(std::floor(x[k] / min_d));
        return c;
    };
    std::vector<std::pair<Cell, std::size_t>> binned;
    for (std::size_t k = 0; k < at_start.size(); ++k) binned.emplace_back(cell_of(at_start[k]), k);
    std::sort(binned.begin(), binned.end());
    auto near_solid = [&](const V& x) {
        const Cell home = cell_of(x);
        int around = 1;
        for (int k = 0; k < Dim; ++k) around *= 3;
        for (int o = 0; o < around; ++o) {
            Cell c = home;
            for (int k = 0, rest = o; k < Dim; ++k, rest /= 3) c[static_cast<std::size_t>(k)] += rest % 3 - 1;
            const auto first = std::lower_bound(binned.begin(), binned.end(), std::make_pair(c, std::size_t{0}));
            for (auto it = first; it != binned.end() && it->first == c; ++it)
                if (norm2(x - at_start[it->second]) < min_d * min_d) return true;
        }
        return false;
    };
    for (std::size_t i = 0; i < P.size(); ++i) {
        bool drop = false;
        if (P.kind[i] == Kind::Fluid) drop = inside_solid(P.x[i]) || near_solid(P.x[i]);
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

void Simulation2D::set_solid_section(std::string name, std::vector<SolidSection::Quad> cells, const std::vector<V>& reference,
                                     SolidSection::Vertices vertices) {
    const WallGeometry g = geometry_;
    section_ = SolidSection(std::move(name), std::move(cells), reference, std::move(vertices),
                            [g](const V& p) { return inside_tank(g, p); }, g.thickness, s_.dp);
}

}  // namespace sphfsi::fluid
