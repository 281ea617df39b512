// Simulation2D: time stepping. The integrators (semi-implicit Euler, velocity Verlet, predictor-corrector,
// PCISPH's predictive-corrective step), the solid forces they accumulate, and the window loop (advance).
#include "sphfsi/fluid/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "format.hpp"
#include "sphfsi/fluid/continuity.hpp"
#include "sphfsi/fluid/kernel_dispatch.hpp"
#include "sphfsi/fluid/wall_boundary.hpp"
#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::fluid {

using protocol::SolverError;

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

void Simulation2D::step_symplectic(double dt, double t_after) {
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
    drift(dt, dt);
    st_.t = t_after;
    st_.rates_fresh = false;
}

void Simulation2D::integrate_densities(double dt) {
    if (!continuity_ || dt == 0.0) return;
    density_rates();
    auto& P = st_.P;
    const bool wall_cont = s_.wall == WallModel::Dummy;
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid || (wall_cont && is_boundary(P.kind[i]))) P.rho[i] += P.drho[i] * dt;
    }
}

void Simulation2D::drift(double dt, double density_dt) {
    // Densities first, from the current velocities at the positions the grid still matches; then positions.
    integrate_densities(density_dt);
    auto& P = st_.P;
    const long long n = static_cast<long long>(P.size());
#pragma omp parallel for schedule(static)
    for (long long q = 0; q < n; ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        if (P.kind[i] == Kind::Fluid) P.x[i] += P.v[i] * dt;
    }
}

void Simulation2D::step_verlet(double dt, double t_after) {
    // Velocity Verlet (kick-drift-kick): the rates of the previous evaluation start the step, one force
    // evaluation per step at the new positions and densities. Integrated densities take the trapezoid of
    // their rate at fixed v^{n+1/2}: half with drho(x^n), half with drho(x^{n+1}) in the evaluation, before
    // the pressures. drho depends on the positions, so taking it all at x^n (as a drift like the
    // positions' would) leaves an O(dt^2) error a step: first order, measured on a dam break (fluid.integrator_order).
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
    drift(dt, half);
    st_.t = t_after;
    // A re-initialisation due at the end of this step comes before its evaluation, which the closing half-kick
    // and the next step use; after the step it would throw that evaluation away. It replaces the densities
    // by sums at x^{n+1}, so the second half of the update is then not due.
    if (reinitialisation_due(st_.step + 1))
        reinitialise_densities();
    else
        density_dt_at_evaluation_ = half;
    evaluate();
    accumulate_solid_forces(half);
    kick();
    st_.rates_fresh = true;  // a^{n+1} at (x^{n+1}, rho^{n+1}, v^{n+1/2}) starts the next step
}

void Simulation2D::step_predictor_corrector(double dt, double t_after) {
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
    st_.t = t_after;
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

double Simulation2D::step_pcisph(double dt, double t_after, bool adaptive, WindowStats& ws) {
    auto& P = st_.P;
    const std::size_t n = P.size();
    const long long nn = static_cast<long long>(n);
    pci_.resize(n);
    const double dt_whole = dt;
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
            // The walls follow clamp_negative as the fluid's pressures do (and as every other model's walls do):
            // they were clamped here whatever the scene said (a review, 2026-11-28).
            return pcisph_solve(P, grid_, kw, kg, pcisph_, dt, pci_, [&] {
                extrapolate_boundary_state(P, grid_, kw, rates_.gravity, s_.clamp_negative, [&](double) { return s_.rho0; },
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
    st_.t = dt == dt_whole ? t_after : st_.t + dt;  // a halved step does not reach t_after
    st_.rates_fresh = false;
    return dt;
}

double Simulation2D::take_step(double dt, double t_after, bool adaptive, WindowStats& ws) {
    stepping_ = true;
    switch (s_.pressure == PressureModel::Pcisph ? Integrator::SymplecticEuler : s_.integrator) {
        case Integrator::SymplecticEuler:
            if (s_.pressure == PressureModel::Pcisph)
                dt = step_pcisph(dt, t_after, adaptive, ws);
            else
                step_symplectic(dt, t_after);
            break;
        case Integrator::VelocityVerlet: step_verlet(dt, t_after); break;
        case Integrator::PredictorCorrector: step_predictor_corrector(dt, t_after); break;
    }
    ++st_.step;
    stepping_ = false;
    // Velocity Verlet re-initialises inside its step, before its one evaluation (step_verlet).
    if (s_.integrator != Integrator::VelocityVerlet && reinitialisation_due(st_.step)) reinitialise_densities();
    const StepCheck checked = check_state(dt);
    ws.max_wall_crossings = std::max(ws.max_wall_crossings, checked.wall_crossings);
    if (s_.pressure != PressureModel::Pcisph)
        ws.max_density_error = std::max(ws.max_density_error, (std::max(checked.rho_max, st_.rho_max) - s_.rho0) / s_.rho0);
    return dt;
}

// Far from t = 0 a double's spacing outgrows the step (0.125 s at t = 1e15 s, against about 1e-4 s): t + dt
// is t, and the adaptive loop stepped for ever at one time (a review, 2026-11-28). "diverged", as a step below
// its floor is: the window may have begun (bad_state would say that nothing had changed; docs/protocol.md).
void Simulation2D::require_clock_moves(double dt) const {
    if (!(st_.t + dt > st_.t))
        throw protocol::SolverError("diverged", "step " + std::to_string(st_.step) + " at t = " + fmt(st_.t) +
                                                     " s: a step of " + fmt(dt) +
                                                     " s does not move the clock (a double's spacing there is " +
                                                     fmt(std::nextafter(st_.t, INFINITY) - st_.t) +
                                                     " s); start the run nearer t = 0");
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
            require_clock_moves(dt);
            if (!st_.rates_fresh) evaluate();
            const double taken = take_step(dt, k + 1 == substeps ? t_end : st_.t + dt, false, ws);  // no drift from summing dt
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
            require_clock_moves(dt);
            const double taken = take_step(dt, last ? t_end : st_.t + dt, true, ws);
            record(taken);
        }
    }
    if (ws.steps == 0) ws.dt_min = 0.0;
    if (step_log_) {
        step_log_->flush();  // a window's lines are on disk when its reply goes out
        // One that can no longer be written (a full disk) would lose every line after it without a word: the
        // run stops; the record holds everything up to the window before this one.
        if (!*step_log_)
            throw protocol::SolverError("internal", "cannot write step_log file '" + s_.step_log + "' after step " +
                                                        std::to_string(st_.step) + " at t = " + fmt(st_.t) + " s");
    }
    return ws;
}

}  // namespace sphfsi::fluid
