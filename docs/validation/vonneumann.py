"""Von Neumann (linear) stability bound of SPH's acoustic modes on a square 2D lattice.

Linearised about rest (density rho0, spacing dp, V = dp^2), the symmetric pressure gradient
-sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij with p' = c^2 rho', and either the continuity equation or
summation densities, give for a plane wave exp(i k.x):
    omega^2 = c^2 V^2 G_p(k) . G_rho(k),   G(k) = sum_j grad W(r_j) sin(k . r_j)   (j over lattice neighbours)
with G_p from the pressure-gradient kernel and G_rho from the density kernel (summation: the gradient of the
density kernel; continuity: the gradient kernel). Symplectic Euler with drho from v^{n+1} and velocity
Verlet are leapfrog-type: stable iff omega dt <= 2, so the acoustic CFL number lambda = c dt / h must
satisfy lambda <= 2 / (h V max_k sqrt(G_p . G_rho)). Kernels as in fluid/include/sphfsi/fluid/kernels.hpp.
Where G_p . G_rho < 0 for some k (two different kernels: the thesis's poly6 densities with spiky pressure
gradients), omega^2 < 0: that mode grows at rest at the rate gamma = c V sqrt(-G_p . G_rho) whatever the
step, by exp(gamma dt) = exp(lambda h gamma / c) a step; printed as h gamma_max / c.
usage: /usr/bin/python3 docs/validation/vonneumann.py
"""
import numpy as np

PI = np.pi


def grad_factor(kind, r, h):
    """W'(r) / r of the code's 2D kernels."""
    q = r / h
    if kind == "wendland":
        a = 7.0 / (4 * PI * h * h)
        return np.where(q < 2, -5.0 * a * (1 - q / 2) ** 3 / h ** 2, 0.0)
    if kind == "cubic_spline":
        s = 10.0 / (7 * PI * h * h)
        return np.where(q < 1, s * (-3.0 + 2.25 * q) / h ** 2,
                        np.where(q < 2, -0.75 * s * (2 - q) ** 2 / (np.maximum(q, 1e-300) * h * h), 0.0))
    if kind == "gaussian":
        tail = np.exp(-9.0)
        s = 1.0 / (PI * h * h * (1 - 10 * tail))
        return np.where(q < 3, -2.0 * s * np.exp(-q * q) / h ** 2, 0.0)
    if kind == "poly6":
        R = 2 * h
        c = 4.0 / (PI * R ** 8)
        d = R * R - r * r
        return np.where(d > 0, -6.0 * c * d * d, 0.0)
    if kind == "spiky":
        R = 2 * h
        c = 10.0 / (PI * R ** 5)
        d = R - r
        return np.where(d > 0, -3.0 * c * d * d / r, 0.0)
    raise ValueError(kind)


def bound(h_over_dp, k_p, k_rho, n=181):
    h, dp = h_over_dp, 1.0
    R = int(np.ceil(3 * h)) + 1
    m, nn = np.meshgrid(np.arange(-R, R + 1), np.arange(-R, R + 1))
    rx, ry = m.ravel() * dp, nn.ravel() * dp
    r = np.hypot(rx, ry)
    keep = r > 0
    rx, ry, r = rx[keep], ry[keep], r[keep]
    fp, fr = grad_factor(k_p, r, h), grad_factor(k_rho, r, h)
    ks = np.linspace(-PI / dp, PI / dp, n)
    best, worst = 0.0, 0.0
    for kx in ks:
        s = np.sin(kx * rx[None, :] + ks[:, None] * ry[None, :])
        Gp = np.stack([s @ (fp * rx), s @ (fp * ry)], -1) * dp * dp
        Gr = np.stack([s @ (fr * rx), s @ (fr * ry)], -1) * dp * dp
        product = np.sum(Gp * Gr, -1)
        best = max(best, float(np.max(product)))
        worst = min(worst, float(np.min(product)))
    hw = h * np.sqrt(best)          # h omega_max / c
    hg = h * np.sqrt(max(0.0, -worst))  # h gamma_max / c: growth at rest (0: none)
    return 2.0 / hw, hw, hg


if __name__ == "__main__":
    cases = [("wendland", "wendland", "wendland"), ("cubic_spline", "cubic_spline", "cubic_spline"),
             ("gaussian", "gaussian", "gaussian"), ("mueller, summation (poly6 densities, spiky pressure)", "spiky", "poly6"),
             ("mueller, continuity (spiky gradients)", "spiky", "spiky")]
    for hd in (1.5,):
        for name, kp, kr in cases:
            lam, hw, hg = bound(hd, kp, kr)
            grows = f"; modes grow at rest, h gamma_max / c = {hg:.3f}" if hg > 1e-6 else ""
            print(f"h = {hd} dp, {name}: h omega_max / c = {hw:.3f} -> leapfrog-type schemes stable for cfl <= {lam:.2f}{grows}")
    for hd in (1.0, 1.1, 1.2, 1.3, 1.5, 1.7, 2.0):
        lam, hw, hg = bound(hd, "spiky", "poly6")
        print(f"mueller, summation, h = {hd} dp: h gamma_max / c = {hg:.3f} ({hg / hw:.3f} of h omega_max / c)")
