// Implicit (strongly coupled) schemes: fixed-point iterations on the interface displacement within
// each window, with constant relaxation, Aitken dynamic relaxation (Kuettler & Wall 2008) or the
// interface quasi-Newton IQN-ILS (Degroote, Bathe & Vierendeels 2009).
#include <Eigen/Dense>
#include <cmath>
#include <deque>
#include <sstream>
#include <vector>

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

// Proposes the next iterate x_{k+1} from x_k and H(x_k) = x~_k. An iterate is the interface displacements
// (its first np entries: the primary data, whose residual drives the relaxation factor, the least squares
// and the convergence test) followed by the interface velocities (secondary data, as in preCICE: updated
// with the same factor or the same combination of secant pairs). The fluid's force depends on the velocity
// too (the wall acceleration (v1 - v0) / dt in its wall pressure, the added mass): an unrelaxed velocity
// would feed the structure's raw answer back and diverge as soon as the added mass exceeds about twice the
// structure's, whatever the displacement's relaxation. Relaxed alike, displacement and velocity remain the
// structure's answer to one and the same (combined) force, so a zero displacement residual also means
// consistent velocities.
class Accelerator {
public:
    virtual ~Accelerator() = default;
    virtual void begin_window() = 0;
    virtual Vec next(const Vec& x, const Vec& x_tilde, Eigen::Index np) = 0;
    // `converged`: whether the window met its tolerance (a capped window's secant pairs are not kept).
    virtual void end_window(bool /*converged*/) {}
};

class ConstantRelaxation : public Accelerator {
public:
    explicit ConstantRelaxation(double w) : w_(w) {}
    void begin_window() override {}
    Vec next(const Vec& x, const Vec& xt, Eigen::Index) override { return x + w_ * (xt - x); }

private:
    double w_;
};

class Aitken : public Accelerator {
public:
    explicit Aitken(double w0) : w0_(w0) {}
    void begin_window() override { have_prev_ = false; }
    Vec next(const Vec& x, const Vec& xt, Eigen::Index np) override {
        const Vec r_all = xt - x;
        Vec r = r_all.head(np);
        if (!have_prev_) {
            w_ = w0_;  // the first iteration of a window starts from the scene's relaxation factor
        } else {
            Vec dr = r - r_prev_;
            double denom = dr.squaredNorm();
            if (denom > 0) w_ = -w_ * r_prev_.dot(dr) / denom;
        }
        r_prev_ = r;
        have_prev_ = true;
        return x + w_ * r_all;
    }

private:
    double w0_, w_ = 0.0;
    Vec r_prev_;
    bool have_prev_ = false;
};

class IqnIls : public Accelerator {
public:
    IqnIls(double w0, int reuse) : w0_(w0), reuse_(reuse) {}
    void begin_window() override {
        have_prev_ = false;
        V_.clear();
        W_.clear();
    }
    Vec next(const Vec& x, const Vec& xt, Eigen::Index np) override {
        const Vec r_all = xt - x;
        Vec r = r_all.head(np);
        if (have_prev_) {
            V_.push_front(r - r_prev_);
            W_.push_front(xt - xt_prev_);
        }
        r_prev_ = r;
        xt_prev_ = xt;
        have_prev_ = true;
        std::size_t cols = V_.size();
        for (const auto& old : past_) cols += old.first.size();
        if (cols == 0) return x + w0_ * r_all;
        // V: differences of the displacement residuals; W: differences of the images, velocities included.
        Eigen::MatrixXd V(r.size(), static_cast<Eigen::Index>(cols)), W(xt.size(), static_cast<Eigen::Index>(cols));
        Eigen::Index c = 0;
        auto add = [&](const std::deque<Vec>& vs, const std::deque<Vec>& ws) {
            for (std::size_t i = 0; i < vs.size(); ++i, ++c) {
                V.col(c) = vs[i];
                W.col(c) = ws[i];
            }
        };
        add(V_, W_);
        for (const auto& [vs, ws] : past_) add(vs, ws);
        // Filter (QR2, Haelterman et al. 2016): Gram-Schmidt over the columns, newest first; a column whose
        // part orthogonal to the ones kept is below `filter` of its own norm is dropped with its W column.
        // Nearly dependent secant pairs (an old window's, or one that the fluid's pressure clamp made flat)
        // otherwise let the least squares fit the residual with huge coefficients and throw the iterate far
        // off: with the fluid's force depending on the iterate (added mass) that happened within the first
        // windows of the added-mass scene.
        const double filter = 1e-2;
        Eigen::MatrixXd Q(V.rows(), V.cols());
        std::vector<Eigen::Index> kept;
        for (Eigen::Index j = 0; j < V.cols(); ++j) {
            Vec q = V.col(j);
            const double n0 = q.norm();
            if (!(n0 > 0.0)) continue;
            for (int pass = 0; pass < 2; ++pass)  // twice: Gram-Schmidt is then orthogonal to round-off
                for (std::size_t k = 0; k < kept.size(); ++k) q -= Q.col(static_cast<Eigen::Index>(k)).dot(q) * Q.col(static_cast<Eigen::Index>(k));
            const double n1 = q.norm();
            if (n1 < filter * n0) continue;
            Q.col(static_cast<Eigen::Index>(kept.size())) = q / n1;
            kept.push_back(j);
        }
        if (kept.empty()) return x + w0_ * r_all;
        Eigen::MatrixXd Vk(V.rows(), static_cast<Eigen::Index>(kept.size())), Wk(W.rows(), static_cast<Eigen::Index>(kept.size()));
        for (std::size_t k = 0; k < kept.size(); ++k) {
            Vk.col(static_cast<Eigen::Index>(k)) = V.col(kept[k]);
            Wk.col(static_cast<Eigen::Index>(k)) = W.col(kept[k]);
        }
        // Least squares min |V a + r| over the kept columns.
        Vec a = Vk.colPivHouseholderQr().solve(-r);
        return xt + Wk * a;
    }
    // The last iteration's pair is not added (preCICE adds it): measured, it cost iterations or changed
    // nothing in every scene we tried (docs/coupling.md). A window that converged in two iterations or fewer
    // stores nothing, and neither does one stopped at max_iterations without converging: its pairs (a
    // clamp, a shock in the fluid) would steer the next iqn_reuse windows, and the filter only removes
    // dependent columns, not wrong ones (a review).
    void end_window(bool converged) override {
        if (reuse_ == 0 || V_.empty() || !converged) return;
        past_.emplace_front(V_, W_);
        while (static_cast<int>(past_.size()) > reuse_) past_.pop_back();
    }

private:
    double w0_;
    int reuse_;
    std::deque<Vec> V_, W_;
    std::deque<std::pair<std::deque<Vec>, std::deque<Vec>>> past_;
    Vec r_prev_, xt_prev_;
    bool have_prev_ = false;
};

class ImplicitScheme : public CouplingScheme {
public:
    ImplicitScheme(const Value& c, Session& s, Log log, std::unique_ptr<Accelerator> acc)
        : session_(s), log_(std::move(log)), acc_(std::move(acc)), predictor_(c.at("predictor").as_string()),
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
        acc_->begin_window();
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
            o.converged = o.residual <= bound;
            if (o.converged || k + 1 >= max_iter_) {
                s.force = f;
                o.structure_force = f;
                s.fluid_displacement = to_array(x.head(nd), d);
                s.previous_displacement = s.displacement;
                s.previous_dt = p.dt;
                s.displacement = d_new;
                s.velocity = v_new;
                break;
            }
            x = acc_->next(x, xt, nd);
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
        if (!o.converged) {
            std::ostringstream msg;
            msg << "coupling did not converge in window t = " << p.t << " s after " << o.iterations
                << " iterations (residual " << o.residual << " m; coupling.max_iterations)";
            if (fail_on_cap_)
                o.stop_run = msg.str();
            else
                log_("warning: " + msg.str());
        }
        return o;
    }

private:
    Session& session_;
    Log log_;
    std::unique_ptr<Accelerator> acc_;
    std::string predictor_;
    double tol_rel_, tol_abs_;
    int max_iter_;
    bool fail_on_cap_;
};
}  // namespace

std::unique_ptr<CouplingScheme> make_implicit_scheme(const Value& c, Session& session, Log log) {
    const std::string& scheme = c.at("scheme").as_string();
    double w = c.at("relaxation").as_double();
    std::unique_ptr<Accelerator> acc;
    if (scheme == "implicit-fixed") acc = std::make_unique<ConstantRelaxation>(w);
    else if (scheme == "implicit-aitken") acc = std::make_unique<Aitken>(w);
    else acc = std::make_unique<IqnIls>(w, static_cast<int>(c.at("iqn_reuse").as_int()));
    return std::make_unique<ImplicitScheme>(c, session, std::move(log), std::move(acc));
}

}  // namespace sphfsi::coordinator
