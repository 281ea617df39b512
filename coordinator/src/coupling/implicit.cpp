// Implicit (strongly coupled) schemes: fixed-point iterations on the interface displacement within
// each window, each next iterate proposed by an Accelerator (accelerators.hpp).
#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "sphfsi/coordinator/accelerators.hpp"
#include "sphfsi/coordinator/coupling.hpp"

namespace sphfsi::coordinator {
using protocol::F64Array;
using protocol::Fields;
using Vec = Eigen::VectorXd;

namespace {
Vec to_vec(const F64Array& a) { return Eigen::Map<const Vec>(a.values.data(), static_cast<Eigen::Index>(a.values.size())); }
F64Array to_array(const Vec& x, const F64Array& like) {
    F64Array a = like;
    Eigen::Map<Vec>(a.values.data(), x.size()) = x;
    return a;
}

class ImplicitScheme : public CouplingScheme {
public:
    ImplicitScheme(const Value& c, Session& s, Log log, std::unique_ptr<Accelerator> acc)
        : session_(s), log_(std::move(log)), acc_(std::move(acc)), scheme_(c.at("scheme").as_string()),
          predictor_(c.at("predictor").as_string()),
          tol_rel_(c.at("tolerance_rel").as_double()), tol_abs_(c.at("tolerance_abs").as_double()),
          max_iter_(static_cast<int>(c.at("max_iterations").as_int())),
          fail_on_cap_(c.at("on_max_iterations").as_string() == "error") {}

    WindowOutcome run(const WindowPlan& p, InterfaceState& s) override {
        const auto n = s.vertices();
        session_.save("fluid");
        session_.save("structure");
        F64Array d, v;
        predict(predictor_, s, p.dt, d, v);
        // The iterate: displacements, then velocities (see Accelerator).
        const Eigen::Index nd = static_cast<Eigen::Index>(d.values.size());
        Vec x(2 * nd);
        x << to_vec(d), to_vec(v);
        acc_->begin_window(s.secants);
        WindowOutcome o;
        std::uint32_t fluid_substeps = 0, structure_substeps = 0, fluid_iters = 0, structure_iters = 0;
        double fluid_compute = 0, structure_compute = 0, fluid_trip = 0, structure_trip = 0;
        for (int k = 0;; ++k) {
            if (k > 0) {
                session_.restore("fluid");
                session_.restore("structure");
            }
            o.fluid = session_.advance("fluid", p.t, p.dt, p.fluid_substeps, k,
                                       Fields{{"displacement", to_array(x.head(nd), d)},
                                              {"velocity", to_array(x.tail(nd), v)}});
            const F64Array& f = vertex_field("fluid", o.fluid.reply.outputs, "force", n);
            o.structure = session_.advance("structure", p.t, p.dt, p.structure_substeps, k, Fields{{"force", f}});
            const F64Array& d_new = vertex_field("structure", o.structure.reply.outputs, "displacement", n);
            const F64Array& v_new = vertex_field("structure", o.structure.reply.outputs, "velocity", n);
            // The record counts the work of every iteration, not only the last one's.
            fluid_substeps += o.fluid.reply.substeps;
            structure_substeps += o.structure.reply.substeps;
            fluid_iters += o.fluid.reply.solver_iterations;
            structure_iters += o.structure.reply.solver_iterations;
            fluid_compute += o.fluid.reply.compute_s;
            structure_compute += o.structure.reply.compute_s;
            fluid_trip += o.fluid.roundtrip_s;
            structure_trip += o.structure.roundtrip_s;
            Vec xt(2 * nd);
            xt << to_vec(d_new), to_vec(v_new);
            // Converged when |r| <= tol_rel |d~| + tol_abs sqrt(n): tol_abs is an RMS length per vertex.
            // Displacements only: with velocities relaxed alike they then agree too (see Accelerator).
            o.residual = (xt.head(nd) - x.head(nd)).norm();
            o.iterations = static_cast<std::uint32_t>(k + 1);
            double bound = tol_rel_ * xt.head(nd).norm() + tol_abs_ * std::sqrt(static_cast<double>(n));
            // A residual that overflowed is no convergence, though the bound overflows with it (inf <= inf): a
            // structure answering 1e308 m was accepted at once (2026-11-28).
            o.converged = std::isfinite(o.residual) && o.residual <= bound;
            Vec next;
            if (!o.converged && k + 1 < max_iter_) {
                next = acc_->next(x, xt, nd);
                // Aitken's factor is unbounded and a least-squares solve can be ill-conditioned: an iterate that
                // is not finite is the coupling's failure, named here, not the fluid's bad input. The window
                // ends on the last evaluated iterate, as at the iteration cap, so that it is recorded before the
                // run stops (it was thrown past the record before 2026-11-28).
                if (!next.allFinite()) o.stop_run = non_finite_iterate(next, xt, nd, p, k + 1, o.residual);
            }
            if (o.converged || k + 1 >= max_iter_ || !o.stop_run.empty()) {
                s.force = f;
                o.structure_force = f;
                s.fluid_displacement = to_array(x.head(nd), d);
                s.previous_displacement = s.displacement;
                s.previous_dt = p.dt;
                s.displacement = d_new;
                s.velocity = v_new;
                break;
            }
            x = std::move(next);
        }
        acc_->end_window(o.converged);
        o.fluid.reply.substeps = fluid_substeps;
        o.structure.reply.substeps = structure_substeps;
        o.fluid.reply.solver_iterations = fluid_iters;
        o.structure.reply.solver_iterations = structure_iters;
        o.fluid.reply.compute_s = fluid_compute;
        o.structure.reply.compute_s = structure_compute;
        o.fluid.roundtrip_s = fluid_trip;
        o.structure.roundtrip_s = structure_trip;
        if (!o.converged && o.stop_run.empty()) {
            std::ostringstream msg;
            msg << "coupling did not converge in window t = " << p.t << " .. " << p.t + p.dt << " s after " << o.iterations
                << " iterations (residual " << o.residual << " m; coupling.max_iterations)";
            if (fail_on_cap_)
                o.stop_run = msg.str();
            else
                log_("warning: " + msg.str());
        }
        return o;
    }

private:
    // Names the first entry of a proposed iterate (displacements, then velocities) that is not finite, and the
    // largest entry of the structure's last answer `answer` that it was made from: an answer that overflows
    // the accelerator is finite itself (1e308 m), and the user needs to see that the structure gave it.
    std::string non_finite_iterate(const Vec& next, const Vec& answer, Eigen::Index nd, const WindowPlan& p,
                                   int iterations, double residual) const {
        const auto entry = [nd](Eigen::Index j) {
            const bool velocity = j >= nd;
            const Eigen::Index k = velocity ? j - nd : j;
            return std::string(velocity ? "velocity " : "displacement ") + (k % 2 == 0 ? 'x' : 'y') +
                   " at interface vertex " + std::to_string(k / 2);
        };
        Eigen::Index j = 0;
        while (j < next.size() && std::isfinite(next[j])) ++j;
        Eigen::Index largest = 0;
        answer.cwiseAbs().maxCoeff(&largest);
        std::ostringstream msg;
        msg << "coupling diverged: the " << scheme_ << " iterate of window t = " << p.t << " .. " << p.t + p.dt
            << " s is not finite after " << iterations << " iterations (residual " << residual << " m): its "
            << entry(j) << " is " << next[j] << "; the structure last answered " << answer[largest]
            << (largest >= nd ? " m/s" : " m") << " for its " << entry(largest) << ", its largest entry";
        return msg.str();
    }

    Session& session_;
    Log log_;
    std::unique_ptr<Accelerator> acc_;
    std::string scheme_, predictor_;
    double tol_rel_, tol_abs_;
    int max_iter_;
    bool fail_on_cap_;
};
}  // namespace

std::unique_ptr<CouplingScheme> make_implicit_scheme(const Value& c, Session& session, Log log) {
    auto acc = make_accelerator(c.at("scheme").as_string(), c.at("relaxation").as_double(),
                                static_cast<int>(c.at("iqn_reuse").as_int()));
    return std::make_unique<ImplicitScheme>(c, session, std::move(log), std::move(acc));
}

}  // namespace sphfsi::coordinator
