#pragma once
// The implicit schemes' update rules (docs/coupling.md): from an iterate x_k and the structure's answer to it,
// H(x_k) = x~_k, propose x_{k+1}. Constant relaxation, Aitken's dynamic relaxation (Kuettler & Wall 2008) and
// the interface quasi-Newton IQN-ILS (Degroote, Bathe & Vierendeels 2009).
//
// An iterate is the interface displacements (its first np entries: the primary data, whose residual drives
// the relaxation factor, the least squares and the convergence test) followed by the interface velocities
// (secondary data, as in preCICE: updated with the same factor or the same combination of secant pairs).
// The fluid's force depends on the velocity too (the wall acceleration (v1 - v0) / dt in its wall pressure,
// the added mass): an unrelaxed velocity would feed the structure's raw answer back and diverge as soon as
// the added mass exceeds about twice the structure's, whatever the displacement's relaxation. Relaxed alike,
// displacement and velocity remain the structure's answer to one and the same (combined) force, so a zero
// displacement residual also means consistent velocities (when the first iterate is such a pair: the
// predictors', explicit.cpp).
#include <Eigen/Dense>
#include <deque>
#include <memory>
#include <string>

#include "sphfsi/coordinator/session.hpp"

namespace sphfsi::coordinator {

class Accelerator {
public:
    using Vec = Eigen::VectorXd;
    virtual ~Accelerator() = default;
    // `history`: what IQN-ILS keeps across windows (InterfaceState::secants), read and added to until
    // end_window; it must outlive the window.
    virtual void begin_window(SecantHistory& history) = 0;
    virtual Vec next(const Vec& x, const Vec& x_tilde, Eigen::Index np) = 0;
    // `converged`: whether the window met its tolerance (a capped window's secant pairs are not kept).
    virtual void end_window(bool /*converged*/) {}
};

class ConstantRelaxation : public Accelerator {
public:
    explicit ConstantRelaxation(double w) : w_(w) {}
    void begin_window(SecantHistory&) override {}
    Vec next(const Vec& x, const Vec& xt, Eigen::Index) override { return x + w_ * (xt - x); }

private:
    double w_;
};

// w_k = -w_{k-1} r_{k-1}.(r_k - r_{k-1}) / |r_k - r_{k-1}|^2 on the displacement residual, from the scene's
// relaxation factor at each window's first iteration.
class Aitken : public Accelerator {
public:
    explicit Aitken(double w0) : w0_(w0) {}
    void begin_window(SecantHistory&) override { have_prev_ = false; }
    Vec next(const Vec& x, const Vec& xt, Eigen::Index np) override;

private:
    double w0_, w_ = 0.0;
    Vec r_prev_;
    bool have_prev_ = false;
};

// The inverse Jacobian of the residual from least squares over the secant pairs of this window and of the
// last `reuse` converged windows, nearly dependent columns dropped (QR2 filter, Haelterman et al. 2016).
class IqnIls : public Accelerator {
public:
    IqnIls(double w0, int reuse) : w0_(w0), reuse_(reuse) {}
    void begin_window(SecantHistory& history) override;
    Vec next(const Vec& x, const Vec& xt, Eigen::Index np) override;
    void end_window(bool converged) override;

private:
    double w0_;
    int reuse_;
    SecantHistory* history_ = nullptr;
    std::deque<Vec> V_, W_;  // this window's pairs, newest first
    Vec r_prev_, xt_prev_;
    bool have_prev_ = false;
};

// "implicit-fixed", "implicit-aitken" or "implicit-iqn-ils".
std::unique_ptr<Accelerator> make_accelerator(const std::string& scheme, double relaxation, int iqn_reuse);

}  // namespace sphfsi::coordinator
