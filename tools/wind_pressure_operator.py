#!/usr/bin/python3
"""The fluid's pressure term applied to the exact set-up pressure on a wind-basin run's recorded arrangements.

Separates the two ways the closed wind basin (scenarios/wind_basin.toml) can get its pressure force wrong:
the operator on the arrangement the particles have taken, and the pressure field the run holds. For each
frame asked for, over the fluid particles of the section x_from < x < x_to more than one support radius from
the bottom and the nominal surface, it prints the mean x-acceleration as a fraction of the lubrication
theory's -3 tau / (2 rho0 D), of
  - the solver's symmetric term -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij (fluid/.../interaction.hpp),
    uncorrected (pressure.kernel_correction = false; the scene corrects it since 2026-11-26)
    applied to the exact pressure rho0 g (D + b (x - x_mid) - y), b = 3 tau / (2 rho0 g D), on every
    particle, walls included (what the Adami walls aim at);
  - its zeroth-order part -2 p_i / rho_i sum_j V_j grad W_ij (zero on a lattice, whatever p is);
  - its difference part -sum_j V_j (p_j - p_i) grad W_ij / rho_i;
  - the difference part with the kernel gradient correction (Bonet & Lok 1999), exact for a linear field;
  - the symmetric term with the run's own pressures.
The kernel is the Wendland quintic C2 (the scene's); h, the particle mass and rho0 come from the record.
With --window T0,T1 it takes every frame in that time window and ends with their mean: single frames
scatter (at dp = D/20 the zeroth-order part read -0.026 at t = 3.5 s and -0.087 at t = 4 s), so compare
windows. docs/validation.md ("Wind-driven closed basin") quotes its output.

    /usr/bin/python3 tools/wind_pressure_operator.py RUN_DIR --tau 5 --depth 0.04 --times 4.5,8
    /usr/bin/python3 tools/wind_pressure_operator.py RUN_DIR --tau 5 --depth 0.04 --window 6,8
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweeplib.record import open_record  # noqa: E402


def wendland_gradient_factor(r, h):
    """F(r) with grad W_ij = F(r_ij) (x_i - x_j): the 2D Wendland quintic C2, support 2h."""
    alpha = 7.0 / (4.0 * np.pi * h * h)
    q = r / h
    return np.where(q < 2.0, -5.0 * alpha * (1.0 - 0.5 * q) ** 3 / (h * h), 0.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--tau", type=float, required=True, help="surface stress [Pa]")
    ap.add_argument("--depth", type=float, required=True, help="mean water depth D [m]")
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--times", help="comma-separated frame times [s]")
    which.add_argument("--window", help="T0,T1: every frame with T0 <= t <= T1, then their mean [s]")
    ap.add_argument("--x-from", type=float, default=0.1)
    ap.add_argument("--x-to", type=float, default=0.3)
    ap.add_argument("--g", type=float, default=9.81)
    args = ap.parse_args()
    with open_record(args.run_dir) as f:
        info = f["participants/fluid"].attrs
        h, m, rho0 = float(info["h"]), float(info["particle_mass"]), float(info["rho0"])
        frames = f["frames/fluid"]
        times = frames["time"][:]
        D, tau, g = args.depth, args.tau, args.g
        x_mid = 0.5 * (args.x_from + args.x_to)
        b = 3.0 * tau / (2.0 * rho0 * g * D)
        theory = -1.5 * tau / (D * rho0)
        print(f"# fractions of the theory's {theory:.4g} m/s^2 (h = {h:g} m, m = {m:g} kg/m)")
        print("t sym_exact zeroth_exact difference_exact kgc_difference_exact sym_run")
        if args.times:
            picked = [int(np.argmin(abs(times - float(s)))) for s in args.times.split(",")]
        else:
            t0, t1 = (float(s) for s in args.window.split(","))
            picked = [k for k, t in enumerate(times) if t0 - 1e-9 <= t <= t1 + 1e-9]
            if not picked:
                raise SystemExit(f"no frame with {t0} <= t <= {t1} (frames reach t = {times[-1]:g})")
        rows = []
        for k in picked:
            x, rho = frames["position"][k], frames["density"][k][:, 0]
            p, kind = frames["pressure"][k][:, 0], frames["kind"][k][:, 0]
            live = kind != 3  # Kind::Escaped (fluid/.../particles.hpp): left the domain
            x, rho, p, kind = x[live], rho[live], p[live], kind[live]
            exact = rho0 * g * (D + b * (x[:, 0] - x_mid) - x[:, 1])
            inner = np.where((kind == 0) & (x[:, 0] > args.x_from) & (x[:, 0] < args.x_to) &
                             (x[:, 1] > 2 * h) & (x[:, 1] < D - 2 * h))[0]
            sums = np.zeros(5)
            for i in inner:
                d = x[i] - x
                r = np.hypot(d[:, 0], d[:, 1])
                nb = np.where((r < 2 * h) & (r > 0))[0]
                grad = wendland_gradient_factor(r[nb], h)[:, None] * d[nb]
                vol = m / rho[nb]
                moment = ((-d[nb])[:, :, None] * grad[:, None, :] * vol[:, None, None]).sum(0)
                symmetric = lambda pp: -(m * (pp[i] / rho[i] ** 2 + pp[nb] / rho[nb] ** 2))[:, None] * grad
                difference = -((vol * (exact[nb] - exact[i]))[:, None] * grad).sum(0) / rho[i]
                sums += [symmetric(exact).sum(0)[0],
                         (-2.0 * exact[i] / rho[i] * (vol[:, None] * grad).sum(0))[0],
                         difference[0],
                         np.linalg.solve(moment.T, difference)[0],
                         symmetric(p).sum(0)[0]]
            rows.append(sums / len(inner) / theory)
            print(f"{times[k]:g} " + " ".join(f"{v:.3f}" for v in rows[-1]))
        if args.window:
            print(f"mean({len(rows)}) " + " ".join(f"{v:.3f}" for v in np.mean(rows, axis=0)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
