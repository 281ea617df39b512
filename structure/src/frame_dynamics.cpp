#include "sphfsi/structure/frame_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "sphfsi/protocol/solver.hpp"
#include "sphfsi/structure/assembly.hpp"
#include "sphfsi/structure/integrator.hpp"

namespace sphfsi::structure {

using protocol::SolverError;

namespace {
std::string num(double x) {
    std::ostringstream s;
    s.precision(6);
    s << x;
    return s.str();
}

// The components of a node's three dofs, in a full-dof vector's order.
constexpr const char* kComponent[3] = {"ux", "uy", "theta"};

// "at node N (uy)": where the largest entry of a full-dof vector is; a Newton that does not converge names
// where it fails, as every other failure names its node (a kill probe, 2026-11-28).
std::string largest_entry(const Vector& x) {
    Eigen::Index at = 0;
    if (x.size() == 0) return "nowhere";
    x.cwiseAbs().maxCoeff(&at);
    return "at node " + std::to_string(at / 3) + " (" + kComponent[at % 3] + ")";
}
}  // namespace

FrameDynamics::FrameDynamics(StructureConfig config, double t0, bool fresh)
    : config_(std::move(config)), model_(build_model(config_)), loads_(config_, model_), load_switches_(loads_.switch_times()) {
    // One mass matrix for the whole run, in the reference configuration, also for co-rotational runs (the
    // common constant-mass simplification of co-rotational dynamics). Lumped masses are the same in every
    // orientation; a consistent element matrix turned far from its reference orientation shares its inertia
    // out as if it had not turned (its axial m/3, m/6 against its transverse 156/420, 54/420, and the
    // rotation coupling 22L/420, 13L/420), an error that shrinks with the element length squared. The
    // co-rotational energy balance test (tests/structure/test_corotational.cpp) holds to 1e-3 with it.
    M_ = assemble_mass(model_, config_.mass);
    K0_ = assemble_linear_stiffness(model_);

    int wanted = std::max(config_.time.resolved_modes, config_.initial.mode);
    if (config_.damping.kind == DampingKind::Rayleigh) wanted = std::max(wanted, 2);
    modes_ = lowest_modes(model_, K0_, M_, wanted);
    const int elastic = static_cast<int>(modes_.omega2.size()) - modes_.rigid_body;

    setup_damping();

    dt_accuracy_ = std::numeric_limits<double>::infinity();
    if (elastic > 0) {
        const int highest = modes_.rigid_body + std::min(config_.time.resolved_modes, elastic) - 1;
        dt_accuracy_ = accuracy_step(config_.time, modes_.omega(highest));
    }
    // A sine load is sampled at the step ends: its period must be resolved as a mode's is, or a load above
    // half the step rate acts as its alias (5863 Hz moved the beam as 16.7 Hz did, to the digit, a review,
    // 2026-11-27). The coordinator bounds its [load] windows likewise, at 20 points a period.
    auto resolve = [&](const History& h) {
        if (h.kind == History::Kind::Sine) dt_accuracy_ = std::min(dt_accuracy_, 1.0 / (h.frequency * config_.time.steps_per_period));
    };
    for (const auto& p : config_.point_loads) resolve(p.history);
    for (const auto& d : config_.distributed_loads) resolve(d.history);
    if (config_.initial.mode > elastic)
        throw SolverError("bad_config", "structure.initial.mode = " + std::to_string(config_.initial.mode) +
                                            " but the structure has only " + std::to_string(elastic) +
                                            " elastic modes");
    if (fresh) reset(t0);
    else at_rest(t0);
}

void FrameDynamics::setup_damping() {
    const auto& d = config_.damping;
    D_.resize(model_.dof_count(), model_.dof_count());
    if (d.kind == DampingKind::Simple) {
        D_ = d.c * M_;
        rayleigh_alpha_ = d.c;
    } else if (d.kind == DampingKind::Rayleigh) {
        // zeta(omega) = alpha / (2 omega) + beta omega / 2, matched at omega1 and omega2.
        double w1, w2;
        if (d.frequencies) {
            w1 = 2 * std::numbers::pi * (*d.frequencies)[0];
            w2 = 2 * std::numbers::pi * (*d.frequencies)[1];
        } else {
            const int elastic = static_cast<int>(modes_.omega2.size()) - modes_.rigid_body;
            if (elastic < 2)
                throw SolverError("bad_config", "structure.damping.frequencies: give them; the structure has fewer "
                                                "than two elastic modes to take them from");
            w1 = modes_.omega(modes_.rigid_body);
            int second = modes_.rigid_body + std::max(1, std::min(config_.time.resolved_modes, elastic) - 1);
            w2 = modes_.omega(second);
            // Identical parts share their frequencies (two equal cantilevers: modes 1 and 2). Matched at one
            // frequency twice, the pair is the tangent there (zeta 0.064 at mode 3 against a 0.02 target, a
            // review): take the next distinct frequency computed, else ask for them.
            const int computed = static_cast<int>(modes_.omega2.size());
            while (std::abs(w2 - w1) <= 1e-6 * w1 && second + 1 < computed) w2 = modes_.omega(++second);
            if (std::abs(w2 - w1) <= 1e-6 * w1)
                throw SolverError("bad_config", "structure.damping.frequencies: give them; the lowest " +
                                                    std::to_string(computed - modes_.rigid_body) +
                                                    " elastic modes computed share one frequency (" +
                                                    num(w1 / (2 * std::numbers::pi)) + " Hz), and the Rayleigh "
                                                    "pair needs two (raise time.resolved_modes, or give them)");
        }
        const double z1 = d.ratios[0], z2 = d.ratios[1];
        rayleigh_beta_ = 2.0 * (w2 * z2 - w1 * z1) / (w2 * w2 - w1 * w1);
        rayleigh_alpha_ = 2.0 * w1 * z1 - rayleigh_beta_ * w1 * w1;
        if (rayleigh_alpha_ < 0 || rayleigh_beta_ < 0)
            throw SolverError("bad_config", "structure.damping: ratios " + num(z1) + ", " + num(z2) +
                                                " at these frequencies need a negative Rayleigh coefficient (alpha = " +
                                                num(rayleigh_alpha_) + ", beta = " + num(rayleigh_beta_) +
                                                "), i.e. negative damping in some modes");
        D_ = rayleigh_alpha_ * M_ + rayleigh_beta_ * K0_;
        alpha_mass_ = rayleigh_alpha_ * M_;
    }
}

SparseMatrix FrameDynamics::damping(const Vector& u) const {
    if (!turning_damping()) return D_;
    SparseMatrix material;
    corotational_internal_force(model_, u, nullptr, nullptr, &material);
    return rayleigh_alpha_ * M_ + rayleigh_beta_ * material;
}

void FrameDynamics::at_rest(double t0) {
    const int n = model_.dof_count();
    state_ = State{};
    state_.t = t0;
    state_.u = Vector::Zero(n);
    state_.v = Vector::Zero(n);
    state_.a = Vector::Zero(n);
}

void FrameDynamics::reset(double t0) {
    at_rest(t0);
    const auto& init = config_.initial;
    if (init.mode > 0) {
        Vector phi = modes_.shapes.col(modes_.rigid_body + init.mode - 1);
        // An eigenvector's sign is arbitrary (and which eigensolver runs depends on the mesh's size), so the
        // shape is signed to make its largest translation component positive: the same amplitude then starts
        // the structure deflected the same way on every mesh (a review, 2026-11-27). Components within 1e-6 of
        // the largest tie (an antisymmetric mode of a symmetric structure has two, and round-off picked one,
        // which a second review found flipping with the mesh): the one at the smallest x, then y, decides.
        double largest = 0, peak = 0, turn = 0;
        for (int i = 0; i < model_.node_count(); ++i) {
            largest = std::max(largest, phi.segment<2>(3 * i).norm());
            peak = std::max({peak, std::abs(phi[3 * i]), std::abs(phi[3 * i + 1])});
            turn = std::max(turn, std::abs(phi[3 * i + 2]));
        }
        double component = 0;
        Vec2 at{};
        for (int i = 0; i < model_.node_count(); ++i)
            for (int k = 0; k < 2; ++k) {
                const double c = phi[3 * i + k];
                const Vec2& x = model_.nodes[static_cast<std::size_t>(i)];
                const bool first = component == 0 || x.x() < at.x() || (x.x() == at.x() && x.y() < at.y());
                if (std::abs(c) >= (1.0 - 1e-6) * peak && first) component = c, at = x;
            }
        // A mode whose translations are round-off beside its rotations moves no node.
        if (!(largest > 1e-9 * turn * model_.characteristic_length))
            throw SolverError("bad_config", "structure.initial.mode = " + std::to_string(init.mode) +
                                                ": that mode turns the nodes without moving any, and mode_amplitude is "
                                                "the largest nodal translation; choose another mode");
        state_.u = (component < 0.0 ? -1.0 : 1.0) * init.mode_amplitude / largest * phi;
    }
    if (init.static_equilibrium || !init.preload.empty()) {
        const Vector preload = point_load_vector(model_, init.preload, "structure.initial.preload");
        const bool scene = init.static_equilibrium;
        solve_static(
            [&](const Vector& u) {
                return scene ? Vector(loads_.at(t0, u, !linear()) + preload) : preload;
            },
            config_.newton.load_steps);
    }
    equilibrate_acceleration(Vector());
    const Energies e = energies();
    state_.initial_energy = e.kinetic + e.strain;
    state_.energy_scale = state_.initial_energy;
    // An infinite start (mode_amplitude = 1e200 passed every bound) left the energy check comparing inf with inf,
    // NaN, which silently turned it off (a review, 2026-11-27).
    if (!std::isfinite(state_.initial_energy))
        throw SolverError("bad_config", "structure.initial: the start's strain energy is not a finite number (" +
                                            std::to_string(state_.initial_energy) + "); mode_amplitude or preload is out of all proportion");
}

Vector FrameDynamics::scene_load(double t, History::Side side) const { return loads_.at(t, state_.u, !linear(), side); }

Vector FrameDynamics::internal_force(const Vector& u, SparseMatrix* tangent, double* strain_energy) const {
    if (!linear()) return corotational_internal_force(model_, u, tangent, strain_energy);
    Vector f = K0_ * u;
    if (tangent) *tangent = K0_;
    if (strain_energy) *strain_energy = 0.5 * u.dot(f);
    return f;
}

void FrameDynamics::equilibrate_acceleration(const Vector& extra) {
    balance_acceleration(extra.size() ? Vector(scene_load(state_.t) + extra) : scene_load(state_.t));
}

void FrameDynamics::balance_acceleration(const Vector& load) {
    const Vector f = load - damping(state_.u) * state_.v - internal_force(state_.u);
    Eigen::SimplicialLDLT<SparseMatrix> mass(reduce(M_));
    if (mass.info() != Eigen::Success) throw SolverError("internal", "structure: mass matrix is not positive definite");
    state_.a = model_.T * mass.solve(reduce(f));
}

// Failures inside step() name the step being taken and the time it ends at, as its not_converged does.
void FrameDynamics::check_finite(const Vector& x, const char* quantity, double t) const {
    for (Eigen::Index i = 0; i < x.size(); ++i)
        if (!std::isfinite(x[i]))
            throw SolverError("diverged", "structure: " + std::string(quantity) + " " + kComponent[i % 3] +
                                              " of node " + std::to_string(i / 3) + " is " + num(x[i]) +
                                              " at step " + std::to_string(state_.step + 1) + ", t=" +
                                              num(t) + "; reduce dt_max or check the loads");
}

void FrameDynamics::check_bounded(const Vector& u, double t) const {
    // Finite is not enough: a linear model happily returns 1e295 m. Beyond a thousand times the
    // structure's size the numbers mean nothing (a blown-up coupling or absurd forces).
    const double limit = 1e3 * model_.characteristic_length;
    for (int i = 0; i < model_.node_count(); ++i) {
        const double d = u.segment<2>(3 * i).stableNorm();  // norm() overflows to inf from 1e155 m
        if (d > limit)
            throw SolverError("diverged", "structure: displacement of node " + std::to_string(i) + " is " + num(d) +
                                              " m (more than 1000 times the structure's size) at step " +
                                              std::to_string(state_.step + 1) + ", t=" + num(t) +
                                              "; check the loads or reduce dt_max");
    }
}

// Energy the integrator made: kinetic + strain energy beyond the initial energy plus the loads' work (damping
// and numerical dissipation only take energy away). Newmark and generalized-alpha are unconditionally stable
// for linear problems only: in large co-rotational motions at coarse steps they create energy, slowly and
// then explosively, and a run could complete with 19 times the loads' work as kinetic and strain energy (a
// review, 2026-11-27: beam_only, P L^2 / EI = 2, Newmark at 5.0e-4 s; docs/validation.md "Structure step").
// The scale is the largest energy the structure has had or been given so far, max(initial energy + |load
// work|, kinetic + strain): the motion's energy, counted once. Not the present one: a structure under a
// sudden constant load comes back to its start at rest every period, where the present energies are all
// near zero and round-off would be divided by nothing. It is kept in the
// state (and the checkpoint), with the baseline, so a resumed run checks as the uninterrupted one (a review
// found a resume's INIT rebuilding the baseline at the resume time, which stopped a resumed run at once).
// Measured with the default: coupled runs of the scenes reach 0.005 - 0.031 of the scale (the elastic gate
// at 1 - 4 mm to 0.4 s the most); the co-rotational cantilever above stops at t = 0.30 s (Newmark, 5.0e-4 s)
// and 0.28 s (generalized-alpha, 1.43e-3 s), where both ended "completed" with 0.13 and 0.78 of the scale
// created (docs/validation.md "Structure step").
void FrameDynamics::check_energy(const Energies& e) {
    if (std::isnan(state_.initial_energy)) return;
    const double present = std::max(state_.initial_energy + std::abs(e.external_work), e.kinetic + e.strain);
    state_.energy_scale = std::max(state_.energy_scale, present);
    const double limit = config_.failure.max_energy_created;
    if (limit <= 0.0) return;
    const double created = e.kinetic + e.strain - e.external_work - state_.initial_energy;
    const double scale = state_.energy_scale;
    if (!(created > limit * scale)) return;
    int fastest = 0;
    for (int i = 1; i < model_.node_count(); ++i)
        if (state_.v.segment<2>(3 * i).norm() > state_.v.segment<2>(3 * fastest).norm()) fastest = i;
    throw SolverError("diverged", "structure: step " + std::to_string(state_.step) + ", t=" + num(state_.t) +
                                      ": energy created " + num(created) + " J (kinetic " + num(e.kinetic) + " + strain " +
                                      num(e.strain) + " - load work " + num(e.external_work) + " - initial " +
                                      num(state_.initial_energy) + "), " + num(created / scale) +
                                      " of the largest of initial energy + |load work| and kinetic + strain so far (" +
                                      num(scale) + " J), above failure.max_energy_created = " + num(limit) +
                                      "; fastest node " + std::to_string(fastest) + " at " +
                                      num(state_.v.segment<2>(3 * fastest).norm()) +
                                      " m/s. The integrator is creating energy: reduce time.dt_max, lower "
                                      "time.rho_inf, or use backward_euler");
}

// Newton's residual cannot drop below the round-off of the internal forces, ~eps |u| EA / L0 per element
// for stiff axial members (measured: 1.6e-8 of the force scale for 1000 elements). When the residual is
// already small (below sqrt(tol) of the scale, where quadratic convergence would take it below tol in one
// more iteration) but stops halving, it sits on that floor: further iterations only stir round-off.
bool FrameDynamics::round_off_floor(int k, double norm, double previous, double scale, double tol) {
    return k >= 2 && norm > 0.5 * previous && norm <= std::sqrt(tol) * scale;
}

StepReport FrameDynamics::step(double h, const Vector& extra, std::optional<double> t_after) {
    if (!(h > 0) || !std::isfinite(h)) throw SolverError("internal", "structure: step size " + num(h));
    const double t1 = t_after.value_or(state_.t + h);
    // Loads at both ends of the step, on the configuration at its start, each as seen from inside the step: a
    // load switched on or off at an end counts as it is within the step (steps that land on a switch then
    // apply a pulse's impulse exactly; StructureSolver::advance lands its adaptive steps on them). A step
    // that a switch falls inside (sub-steps counted by the coupling, which cannot land there) takes the
    // loads' mean over the step at both ends, constant through it: sampled at its ends, a pulse inside it was
    // lost and one that started inside it was applied as a ramp over the whole step.
    const auto next_switch = std::upper_bound(load_switches_.begin(), load_switches_.end(), state_.t);
    const bool switch_inside = next_switch != load_switches_.end() && *next_switch < t1;
    const bool starts_at_switch =
        state_.step > 0 && std::binary_search(load_switches_.begin(), load_switches_.end(), state_.t);
    Vector fe0 = switch_inside ? loads_.mean(state_.t, t1, state_.u, !linear()) : scene_load(state_.t, History::Side::Right);
    Vector fe1 = switch_inside ? fe0 : scene_load(t1, History::Side::Left);
    if (extra.size()) {
        fe0 += extra;
        fe1 += extra;
    }
    check_finite(fe1, "load", t1);
    // A step that starts where a scene load switches on or off (adaptive steps land there) starts from the
    // acceleration of the load after the switch: the one the step before ended with belongs to the load
    // before it, and the integrators' a_n would carry the jump into this step as a spurious force (a 1 ms
    // pulse on the cantilever then tripped failure.max_energy_created; a review, 2026-11-28). A mean step
    // is bracketed the same way, starting from the mean's acceleration and ending (below) re-balanced under
    // the load at its end, so that every integrator applies h times the mean, the loads' impulse, whatever
    // a_n weighs in it (Newmark and generalized-alpha; a review, 2026-11-29: without the brackets, Newmark
    // took six times a pulse that began where the step did, and half of one that ended where it did).
    if (switch_inside || starts_at_switch) balance_acceleration(fe0);
    const StepCoefficients c = step_coefficients(config_.time.integrator, config_.time.rho_inf, h);
    const double am = c.alpha_m, af = c.alpha_f;
    const Vector& un = state_.u;
    const Vector& vn = state_.v;
    const Vector& an = state_.a;

    // The part of the weighted balance that belongs to time n (zero for backward Euler / Newmark).
    Vector rest = Vector::Zero(un.size());
    if (am != 0.0) rest += am * (M_ * an);
    // Co-rotational stiffness-proportional damping acts on the elements' deformation over the step
    // (corotational_deformation_damping), not on D v: its rate stands for the weighted time's, and rigid
    // motion, however far it turns in a step, is not damped. The mass part alpha M v stays in D.
    const SparseMatrix& D = turning_damping() ? alpha_mass_ : D_;
    if (af != 0.0) rest += af * (D * vn + internal_force(un) - fe0);

    Vector u = un, v1, a1, fint;
    double strain = 0.0;  // at the last evaluated u, which the step ends at (check_energy)
    SparseMatrix Kt, Kd;  // Kd: the deformation damping's tangent
    // The elements' deformation at the step's start, once: every Newton iterate measures from it.
    const std::vector<Eigen::Vector3d> deformed = turning_damping() ? corotational_deformations(model_, un)
                                                                    : std::vector<Eigen::Vector3d>{};
    auto residual = [&](double& scale, bool want_tangent) {
        const Vector du = u - un;
        a1 = c.c0 * du - c.c1 * vn - c.c2 * an;
        v1 = c.c3 * du + c.c4 * vn + c.c5 * an;
        fint = internal_force(u, want_tangent ? &Kt : nullptr, &strain);
        Vector damping = (1.0 - af) * (D * v1);
        if (turning_damping())
            damping += rayleigh_beta_ * corotational_deformation_damping(model_, u, deformed, h, want_tangent ? &Kd : nullptr);
        const Vector inertia = (1.0 - am) * (M_ * a1);
        const Vector R = inertia + damping + (1.0 - af) * (fint - fe1) + rest;
        scale = std::max({reduce(inertia).norm(), reduce(damping).norm(), reduce(fint).norm(), reduce(fe1).norm(),
                          reduce(rest).norm()});
        return reduce(R);
    };
    auto effective = [&](const SparseMatrix& K) {
        SparseMatrix S = (1.0 - am) * c.c0 * M_ + (1.0 - af) * K;
        if (config_.damping.kind != DampingKind::None) S += (1.0 - af) * c.c3 * D;
        if (turning_damping()) S += rayleigh_beta_ * Kd;
        return reduce(S);
    };

    StepReport report;
    double scale = 0;
    if (linear()) {
        // The balance is affine in u: one solve with the factorization of this step size is exact.
        if (h != factorized_h_) {
            if (!solver_.factorize(effective(K0_)))
                throw SolverError("internal", "structure: step " + std::to_string(state_.step + 1) + ", t=" + num(t1) +
                                                  ": singular effective matrix at dt=" + num(h));
            factorized_h_ = h;
        }
        const Vector r = residual(scale, false);
        u += model_.T * solver_.solve(-r);
        residual(scale, false);  // velocity and acceleration of the solution
        report.iterations = 1;
    } else {
        const double tol = config_.newton.tolerance;
        const int max_it = config_.newton.max_iterations;
        factorized_h_ = -1;  // the shared solver now holds a tangent, not the linear matrix
        double previous = std::numeric_limits<double>::infinity();
        for (int k = 0;; ++k) {
            const Vector r = residual(scale, true);
            const double norm = r.norm();
            report.residual = scale > 0 ? norm / scale : 0.0;
            if (round_off_floor(k, norm, previous, scale, tol)) break;
            previous = norm;
            if (!std::isfinite(norm)) {
                check_finite(u, "displacement", t1);
                check_finite(fint, "internal force", t1);
                throw SolverError("diverged", "structure: step " + std::to_string(state_.step + 1) + ", t=" + num(t1) +
                                                  ", dt=" + num(h) + ": Newton residual is not finite with finite "
                                                  "displacements and internal forces (the loads, inertia or damping "
                                                  "overflowed); reduce dt_max or check the loads");
            }
            if (norm <= tol * scale || scale == 0.0) break;
            if (k == max_it)
                throw SolverError("not_converged",
                                  "structure: step " + std::to_string(state_.step + 1) + ", t=" + num(t1) +
                                      ", dt=" + num(h) + ": Newton residual " + num(norm) + " (relative " +
                                      num(report.residual) + ", tolerance " + num(tol) + ", largest " +
                                      largest_entry(model_.T * r) + ") after " + std::to_string(k) +
                                      " iterations; reduce time.dt_max or raise newton.max_iterations");
            if (!solver_.factorize(effective(Kt)))
                throw SolverError("not_converged", "structure: step " + std::to_string(state_.step + 1) + ", t=" +
                                                       num(t1) + ": singular tangent (buckling?) at Newton "
                                                       "iteration " + std::to_string(k + 1));
            u += model_.T * solver_.solve(-r);
            ++report.iterations;
        }
    }
    check_finite(u, "displacement", t1);
    check_finite(v1, "velocity", t1);
    check_bounded(u, t1);

    state_.external_work += 0.5 * (fe0 + fe1).dot(u - un);
    state_.u = u;
    state_.v = v1;
    state_.a = a1;
    state_.t = t1;
    ++state_.step;
    if (switch_inside) equilibrate_acceleration(extra);  // the mean step's closing bracket (above)
    check_energy(Energies{0.5 * state_.v.dot(M_ * state_.v), strain, state_.external_work});
    return report;
}

// Forces repeat every whole turn of a node, so Newton may land rotations whole turns off (a review saw
// -70.7 rad for -pi/2). The two nodes of an element differ by its bending, far less than half a turn, so
// the rotations are made continuous along the mesh from each part's nodes of fixed rotation (exact), or
// else from one node kept within half a turn of where the increment started (an increment may turn the
// whole structure further: the full circle in one increment turns its tip a whole turn).
void FrameDynamics::unwrap_rotations(Vector& u, const Vector& start) const {
    const int n = model_.node_count();
    std::vector<std::vector<int>> next(static_cast<std::size_t>(n));
    for (const Element& e : model_.elements) {
        next[static_cast<std::size_t>(e.n1)].push_back(e.n2);
        next[static_cast<std::size_t>(e.n2)].push_back(e.n1);
    }
    const Vector moves = model_.T.cwiseAbs() * Vector::Ones(model_.T.cols());  // 0 where a DOF is fixed
    std::vector<char> done(static_cast<std::size_t>(n), 0);
    std::vector<int> queue;
    auto spread = [&] {
        for (std::size_t q = 0; q < queue.size(); ++q)
            for (int j : next[static_cast<std::size_t>(queue[q])])
                if (!done[static_cast<std::size_t>(j)]) {
                    const double from = u[3 * queue[q] + 2];
                    u[3 * j + 2] = from + wrap_angle(u[3 * j + 2] - from);
                    done[static_cast<std::size_t>(j)] = 1;
                    queue.push_back(j);
                }
        queue.clear();
    };
    for (int i = 0; i < n; ++i)
        if (moves[3 * i + 2] == 0.0) done[static_cast<std::size_t>(i)] = 1, queue.push_back(i);
    spread();
    for (int i = 0; i < n; ++i)
        if (!done[static_cast<std::size_t>(i)]) {
            u[3 * i + 2] = start[3 * i + 2] + wrap_angle(u[3 * i + 2] - start[3 * i + 2]);
            done[static_cast<std::size_t>(i)] = 1;
            queue.push_back(i);
            spread();
        }
}

int FrameDynamics::solve_static(const std::function<Vector(const Vector&)>& load, int increments) {
    ReducedSolver solver;
    const double tol = config_.newton.tolerance;
    auto mechanism = [&] {
        return SolverError("bad_config", "structure.supports: the structure can move without deforming (a rigid-body "
                                         "motion or mechanism), so it has no static equilibrium; add supports or "
                                         "start dynamically (initial.static_equilibrium = false, no preload)");
    };
    // Whether it can move without deforming is the geometry's and the supports' question, answered exactly by
    // the modal analysis's rigid motions (modes_.rigid_body). A pivot ratio below 1e-14 stood for it, and
    // refused a cantilever with a 1e-5 m stub (stiff, not singular; a review, 2026-11-28).
    int total = 0;
    if (linear()) {
        if (modes_.rigid_body > 0 || !solver.factorize(reduce(K0_))) throw mechanism();
        state_.u = model_.T * solver.solve(reduce(load(state_.u)));
        state_.v.setZero();
        return 1;
    }
    // Load stepping with Newton in each increment; an increment that fails is halved (up to 10 times).
    double lambda = 0.0, increment = 1.0 / increments;
    int halvings = 0;
    Vector last_residual;  // of the last increment tried, for the message when it stalls
    while (lambda < 1.0 - 1e-14) {
        const double target = std::min(1.0, lambda + increment);
        Vector u = state_.u;
        bool converged = false;
        SparseMatrix Kt;
        double previous = std::numeric_limits<double>::infinity();
        for (int k = 0; k <= config_.newton.max_iterations; ++k) {
            // The load on the iterate's configuration (gravity's and distributed loads' moments turn with the
            // elements): taken at the increment's start, a soft cantilever under its own weight ended 2e-5 of
            // its load out of balance at 10 increments, 1e-3 at one (a review). The tangent leaves out the
            // load's change with u; Newton still converges.
            const Vector f = target * load(u);
            const Vector fint = internal_force(u, &Kt);
            const Vector r = reduce(fint - f);
            last_residual = r;
            const double scale = std::max(reduce(fint).norm(), reduce(f).norm());
            if (!std::isfinite(r.norm())) break;
            if (r.norm() <= tol * scale || scale == 0.0 || round_off_floor(k, r.norm(), previous, scale, tol)) {
                converged = true;
                break;
            }
            previous = r.norm();
            if (k == config_.newton.max_iterations) break;
            // Here only when out of balance: a free structure under no load is at rest where it is.
            if (lambda == 0.0 && k == 0 && modes_.rigid_body > 0) throw mechanism();
            if (!solver.factorize(reduce(Kt))) {
                if (lambda == 0.0 && k == 0) throw mechanism();
                break;
            }
            u += model_.T * solver.solve(-r);
            ++total;
        }
        if (converged) {
            unwrap_rotations(u, state_.u);
            state_.u = u;
            lambda = target;
        } else if (++halvings <= 10) {
            increment *= 0.5;
        } else {
            throw SolverError("not_converged", "structure: static solve stalled at load factor " + num(lambda) +
                                                   " of 1 after 10 halvings of the increment (residual " +
                                                   num(last_residual.norm()) + ", largest " +
                                                   largest_entry(model_.T * last_residual) +
                                                   "; limit load or snap-through?); raise newton.load_steps");
        }
    }
    state_.v.setZero();
    return total;
}

Energies FrameDynamics::energies() const {
    Energies e;
    e.kinetic = 0.5 * state_.v.dot(M_ * state_.v);
    internal_force(state_.u, nullptr, &e.strain);
    e.external_work = state_.external_work;
    return e;
}

}  // namespace sphfsi::structure
