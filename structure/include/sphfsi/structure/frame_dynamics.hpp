#pragma once
// The structural solver proper: M a + D v + f_int(u) = f_ext(t) on the frame model, advanced by the
// implicit one-step integrators of integrator.hpp with Newton iterations (co-rotational) or a single
// solve with a reused factorization (linear). Knows nothing about the coupling protocol.
#include <cstdint>
#include <functional>

#include "sphfsi/structure/config.hpp"
#include "sphfsi/structure/linear_solver.hpp"
#include "sphfsi/structure/loads.hpp"
#include "sphfsi/structure/modal.hpp"
#include "sphfsi/structure/model.hpp"

namespace sphfsi::structure {

// Everything that evolves in time. Copying it is a complete save; restoring a copy and stepping on
// gives bit-identical numbers (the factorization cache depends only on the step size).
struct State {
    double t = 0.0;
    std::uint64_t step = 0;
    Vector u, v, a;             // full-DOF displacement, velocity, (algorithmic) acceleration
    double external_work = 0.0; // integral of f_ext . du, trapezoidal per step [J]
    // check_energy's baseline and scale: the initial state's kinetic + strain energy (NaN: unknown, a run
    // resumed from a checkpoint written before 2026-11-27, which then goes without the check), and the largest
    // of initial energy + |work| and kinetic + strain so far. In the state, so that a resumed run (whose INIT
    // rebuilds the initial state at the resume time) and a restored window check as the uninterrupted run.
    double initial_energy = 0.0;
    double energy_scale = 0.0;
};

struct Energies {
    double kinetic = 0, strain = 0, external_work = 0;
};

struct StepReport {
    int iterations = 0;     // Newton iterations (linear formulation: 1 solve)
    double residual = 0.0;  // final |residual| / force scale (0 for the linear formulation)
};

class FrameDynamics {
public:
    // Builds the model, the matrices and the modes, and sets the initial state of config.initial at t0. A
    // resume passes `fresh` = false: the state is at rest at t0 until the checkpoint's replaces it. The scene's
    // start (a static solve, a mode shape) would be wasted work there, and the static solve ran with the
    // loads of the resume time, which can leave the structure free to move (a resume that then failed INIT
    // where the run had started, a review, 2026-11-27).
    explicit FrameDynamics(StructureConfig config, double t0 = 0.0, bool fresh = true);

    const StructureConfig& config() const { return config_; }
    const Model& model() const { return model_; }
    const SparseMatrix& mass() const { return M_; }
    const SparseMatrix& stiffness() const { return K0_; }  // linear stiffness, reference configuration
    // The damping matrix at displacement u: alpha M + beta K, K the linear stiffness, or for co-rotational
    // elements the material stiffness in their current orientation (a rigid rotation is not damped).
    SparseMatrix damping(const Vector& u) const;
    const Modes& modes() const { return modes_; }
    double rayleigh_alpha() const { return rayleigh_alpha_; }
    double rayleigh_beta() const { return rayleigh_beta_; }
    // Largest step the accuracy criterion allows (see accuracy_step); infinity if no elastic mode.
    double dt_accuracy() const { return dt_accuracy_; }
    // How many effective (time-step) matrices were factorized so far.
    int factorizations() const { return solver_.factorizations(); }

    const State& state() const { return state_; }
    State& state() { return state_; }
    // Sets the initial state of config.initial at t0 (undeformed, mode shape or static equilibrium).
    void reset(double t0);
    // Undeformed and at rest at t0.
    void at_rest(double t0);

    // The scene's own loads at time t, on the current configuration.
    Vector scene_load(double t, History::Side side = History::Side::Right) const;
    const std::vector<double>& load_switch_times() const { return load_switches_; }
    // Internal force at u; the tangent and the strain energy when asked for.
    Vector internal_force(const Vector& u, SparseMatrix* tangent = nullptr, double* strain_energy = nullptr) const;

    // One implicit step of length h. `extra` (full DOFs, may be empty) is added to the scene loads and
    // held constant over the step. `t_after`: the time the step ends at, exactly (a sum t + h can land a hair
    // past a load's switch and take the load early); by default t + h. Throws SolverError not_converged /
    // diverged.
    StepReport step(double h, const Vector& extra, std::optional<double> t_after = std::nullopt);

    // Static equilibrium f_int(u) = load(u) from the current u, in `increments` equal load increments
    // (halved on failure); `load` is evaluated on each Newton iterate's configuration.
    // Sets v = 0 and returns the Newton iterations used.
    int solve_static(const std::function<Vector(const Vector&)>& load, int increments);

    // Acceleration that satisfies the equation of motion for the current u, v at the current time.
    void equilibrate_acceleration(const Vector& extra);

    Energies energies() const;

private:
    // The same under the nodal load `load` (scene loads and extra together).
    void balance_acceleration(const Vector& load);
    bool linear() const { return config_.formulation == Formulation::Linear; }
    // Stiffness-proportional damping of co-rotational elements turns with them.
    bool turning_damping() const { return !linear() && rayleigh_beta_ > 0.0; }
    Vector reduce(const Vector& full) const { return model_.T.transpose() * full; }
    SparseMatrix reduce(const SparseMatrix& full) const { return model_.T.transpose() * full * model_.T; }
    void check_finite(const Vector& x, const char* quantity, double t) const;
    void check_bounded(const Vector& u, double t) const;
    void check_energy(const Energies& e);
    static bool round_off_floor(int iteration, double norm, double previous, double scale, double tol);
    void setup_damping();
    void unwrap_rotations(Vector& u, const Vector& start) const;

    StructureConfig config_;
    Model model_;
    SparseMatrix M_, K0_, D_;  // D_: the damping matrix unless it turns with the elements (damping(u))
    SparseMatrix alpha_mass_;  // Rayleigh's alpha M: co-rotational steps damp the beta part by deformation
    SceneLoads loads_;
    std::vector<double> load_switches_;  // loads_.switch_times()
    Modes modes_;
    double rayleigh_alpha_ = 0, rayleigh_beta_ = 0;
    double dt_accuracy_ = 0;
    State state_;
    ReducedSolver solver_;      // effective matrices of the time steps
    double factorized_h_ = -1;  // linear formulation: the step size the factorization belongs to
};

}  // namespace sphfsi::structure
