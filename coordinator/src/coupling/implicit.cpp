// Implicit (strongly coupled) schemes: fixed-point iterations on the interface displacement within
// each window, with constant relaxation, Aitken dynamic relaxation (Kuettler & Wall 2008) or the
// interface quasi-Newton IQN-ILS (Degroote, Bathe & Vierendeels 2009).
#include <Eigen/Dense>
#include <cmath>
#include <deque>
#include <sstream>

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

// Proposes the next iterate x_{k+1} from x_k and H(x_k) = x~_k.
class Accelerator {
public:
    virtual ~Accelerator() = default;
    virtual void begin_window() = 0;
    virtual Vec next(const Vec& x, const Vec& x_tilde) = 0;
    virtual void end_window() {}
};

class ConstantRelaxation : public Accelerator {
public:
    explicit ConstantRelaxation(double w) : w_(w) {}
    void begin_window() override {}
    Vec next(const Vec& x, const Vec& xt) override { return x + w_ * (xt - x); }

private:
    double w_;
};

class Aitken : public Accelerator {
public:
    explicit Aitken(double w0) : w0_(w0) {}
    void begin_window() override { have_prev_ = false; }
    Vec next(const Vec& x, const Vec& xt) override {
        Vec r = xt - x;
        if (!have_prev_) {
            w_ = w0_;  // the first iteration of a window starts from the scene's relaxation factor
        } else {
            Vec dr = r - r_prev_;
            double denom = dr.squaredNorm();
            if (denom > 0) w_ = -w_ * r_prev_.dot(dr) / denom;
        }
        r_prev_ = r;
        have_prev_ = true;
        return x + w_ * r;
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
    Vec next(const Vec& x, const Vec& xt) override {
        Vec r = xt - x;
        if (have_prev_) {
            V_.push_front(r - r_prev_);
            W_.push_front(xt - xt_prev_);
        }
        r_prev_ = r;
        xt_prev_ = xt;
        have_prev_ = true;
        std::size_t cols = V_.size();
        for (const auto& old : past_) cols += old.first.size();
        if (cols == 0) return x + w0_ * r;
        Eigen::MatrixXd V(r.size(), static_cast<Eigen::Index>(cols)), W(r.size(), static_cast<Eigen::Index>(cols));
        Eigen::Index c = 0;
        auto add = [&](const std::deque<Vec>& vs, const std::deque<Vec>& ws) {
            for (std::size_t i = 0; i < vs.size(); ++i, ++c) {
                V.col(c) = vs[i];
                W.col(c) = ws[i];
            }
        };
        add(V_, W_);
        for (const auto& [vs, ws] : past_) add(vs, ws);
        // Least squares min |V a + r|; the rank-revealing QR drops (nearly) dependent secant pairs.
        Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V);
        qr.setThreshold(1e-10);
        Vec a = qr.solve(-r);
        return xt + W * a;
    }
    void end_window() override {
        if (reuse_ == 0 || V_.empty()) return;
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
        Vec x = to_vec(d);
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
                                       Fields{{"displacement", to_array(x, d)}, {"velocity", v}});
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
            Vec xt = to_vec(d_new);
            // Converged when |r| <= tol_rel |d~| + tol_abs sqrt(n): tol_abs is an RMS length per vertex.
            o.residual = (xt - x).norm();
            o.iterations = static_cast<std::uint32_t>(k + 1);
            double bound = tol_rel_ * xt.norm() + tol_abs_ * std::sqrt(static_cast<double>(n));
            o.converged = o.residual <= bound;
            if (o.converged || k + 1 >= max_iter_) {
                s.force = f;
                s.previous_displacement = s.displacement;
                s.previous_dt = p.dt;
                s.displacement = d_new;
                s.velocity = v_new;
                break;
            }
            // The velocity is not relaxed: the fluid takes the structure's latest, which is consistent
            // with the displacement once the iterations converge.
            v = v_new;
            x = acc_->next(x, xt);
        }
        acc_->end_window();
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
            if (fail_on_cap_) throw std::runtime_error(msg.str());
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
