#include "sphfsi/coordinator/accelerators.hpp"

#include <vector>

namespace sphfsi::coordinator {
using Vec = Accelerator::Vec;

Vec Aitken::next(const Vec& x, const Vec& xt, Eigen::Index np) {
    const Vec r_all = xt - x;
    Vec r = r_all.head(np);
    if (!have_prev_) {
        w_ = w0_;  // the first iteration of a window starts from the scene's relaxation factor
    } else {
        Vec dr = r - r_prev_;
        double denom = dr.squaredNorm();
        if (denom > 0) w_ = -w_ * r_prev_.dot(dr) / denom;
        // A factor of exactly 0 would freeze the iterate, and every later residual difference would be 0 too:
        // the window would sit at it until max_iterations. Start again from the scene's factor.
        if (w_ == 0.0) w_ = w0_;
    }
    r_prev_ = r;
    have_prev_ = true;
    return x + w_ * r_all;
}

void IqnIls::begin_window(SecantHistory& history) {
    history_ = &history;
    have_prev_ = false;
    V_.clear();
    W_.clear();
}

Vec IqnIls::next(const Vec& x, const Vec& xt, Eigen::Index np) {
    const Vec r_all = xt - x;
    Vec r = r_all.head(np);
    if (have_prev_) {
        V_.push_front(r - r_prev_);
        W_.push_front(xt - xt_prev_);
    }
    r_prev_ = r;
    xt_prev_ = xt;
    have_prev_ = true;
    // Earlier windows' pairs fit only an interface of this size (a checkpoint's are checked when read).
    std::size_t cols = V_.size();
    for (const SecantWindow& old : *history_) cols += old.V.size();
    if (cols == 0) return x + w0_ * r_all;
    // V: differences of the displacement residuals; W: differences of the images, velocities included.
    Eigen::MatrixXd V(r.size(), static_cast<Eigen::Index>(cols)), W(xt.size(), static_cast<Eigen::Index>(cols));
    Eigen::Index c = 0;
    for (std::size_t i = 0; i < V_.size(); ++i, ++c) {
        V.col(c) = V_[i];
        W.col(c) = W_[i];
    }
    for (const SecantWindow& old : *history_)
        for (std::size_t i = 0; i < old.V.size(); ++i, ++c) {
            V.col(c) = Eigen::Map<const Vec>(old.V[i].data(), r.size());
            W.col(c) = Eigen::Map<const Vec>(old.W[i].data(), xt.size());
        }
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
            for (std::size_t k = 0; k < kept.size(); ++k) {
                const auto e = Q.col(static_cast<Eigen::Index>(k));
                q -= e.dot(q) * e;
            }
        const double n1 = q.norm();
        if (n1 < filter * n0) continue;
        Q.col(static_cast<Eigen::Index>(kept.size())) = q / n1;
        kept.push_back(j);
    }
    if (kept.empty()) return x + w0_ * r_all;
    const auto n_kept = static_cast<Eigen::Index>(kept.size());
    Eigen::MatrixXd Vk(V.rows(), n_kept), Wk(W.rows(), n_kept);
    for (std::size_t k = 0; k < kept.size(); ++k) {
        Vk.col(static_cast<Eigen::Index>(k)) = V.col(kept[k]);
        Wk.col(static_cast<Eigen::Index>(k)) = W.col(kept[k]);
    }
    // Least squares min |V a + r| over the kept columns.
    Vec a = Vk.colPivHouseholderQr().solve(-r);
    return xt + Wk * a;
}

// The last iteration's pair is not added (preCICE adds it): measured, it cost iterations or changed nothing
// in every scene we tried (docs/coupling.md). A window that converged in two iterations or fewer stores
// nothing, and neither does one stopped at max_iterations without converging: its pairs (a clamp, a shock
// in the fluid) would steer the next iqn_reuse windows, and the filter only removes dependent columns, not
// wrong ones (a review).
void IqnIls::end_window(bool converged) {
    if (reuse_ == 0 || V_.empty() || !converged || !history_) return;
    SecantWindow w;
    for (std::size_t i = 0; i < V_.size(); ++i) {
        w.V.emplace_back(V_[i].data(), V_[i].data() + V_[i].size());
        w.W.emplace_back(W_[i].data(), W_[i].data() + W_[i].size());
    }
    history_->push_front(std::move(w));
    while (static_cast<int>(history_->size()) > reuse_) history_->pop_back();
}

std::unique_ptr<Accelerator> make_accelerator(const std::string& scheme, double relaxation, int iqn_reuse) {
    if (scheme == "implicit-fixed") return std::make_unique<ConstantRelaxation>(relaxation);
    if (scheme == "implicit-aitken") return std::make_unique<Aitken>(relaxation);
    return std::make_unique<IqnIls>(relaxation, iqn_reuse);
}

}  // namespace sphfsi::coordinator
