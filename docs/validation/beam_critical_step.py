"""Critical step of an explicit (central-difference) integrator for the cantilever of
scenarios/beam_only.toml: dt_crit = 2 / omega_max (e.g. Hughes, The Finite Element Method, 2000, sec. 9.3),
omega_max from the same plane frame model sphfsi-structure builds (Euler-Bernoulli frame elements,
axial + Hermite bending, consistent or lumped mass, clamped at x = 0).
usage: /usr/bin/python3 docs/validation/beam_critical_step.py [n_elements]
"""
import sys

import numpy as np
from scipy.linalg import eigh


def frame(n, L=1.0, E=2.1e11, rho=7850.0, t=0.02, b=1.0, lumped=False):
    A, I, le = b * t, b * t ** 3 / 12, L / n
    k = np.zeros((6, 6))
    k[np.ix_([0, 3], [0, 3])] = E * A / le * np.array([[1, -1], [-1, 1]])
    kb = E * I / le ** 3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le ** 2, -6 * le, 2 * le ** 2],
                                     [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le ** 2, -6 * le, 4 * le ** 2]])
    k[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] = kb
    m = np.zeros((6, 6))
    if lumped:
        mm = rho * A * le / 2
        m[np.diag_indices(6)] = [mm, mm, rho * A * le ** 3 / 78, mm, mm, rho * A * le ** 3 / 78]
    else:
        m[np.ix_([0, 3], [0, 3])] = rho * A * le / 6 * np.array([[2, 1], [1, 2]])
        m[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] = rho * A * le / 420 * np.array(
            [[156, 22 * le, 54, -13 * le], [22 * le, 4 * le ** 2, 13 * le, -3 * le ** 2],
             [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le ** 2, -22 * le, 4 * le ** 2]])
    N = 3 * (n + 1)
    K, M = np.zeros((N, N)), np.zeros((N, N))
    for e in range(n):
        idx = list(range(3 * e, 3 * e + 6))
        K[np.ix_(idx, idx)] += k
        M[np.ix_(idx, idx)] += m
    free = list(range(3, N))
    return K[np.ix_(free, free)], M[np.ix_(free, free)]


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    for lumped in (False, True):
        K, M = frame(n, lumped=lumped)
        w2 = eigh(K, M, eigvals_only=True)
        w = np.sqrt(w2[w2 > 0])
        print(f"{n} elements, {'lumped' if lumped else 'consistent'} mass: f1 = {w[0] / (2 * np.pi):.2f} Hz, "
              f"omega_max = {w[-1]:.4g} rad/s, central-difference dt_crit = 2/omega_max = {2 / w[-1]:.3g} s")
