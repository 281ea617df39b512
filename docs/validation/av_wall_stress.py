"""Shear stress that Monaghan's artificial viscosity puts on fluid sliding past a fixed no-slip wall.

Set-up (as in fluid/include/sphfsi/fluid/{viscosity,wall_boundary}.hpp): a square lattice of spacing dp,
fluid in the rows y = (k + 1/2) dp, wall particles in the rows y = -(k + 1/2) dp (3 layers, the default
tank.wall_layers), h = 1.5 dp, Wendland C2 kernel. Every fluid particle moves at v along the wall; the Adami
no-slip ghost velocity of each wall particle is 2 v_wall - v = -v. Monaghan's term acts on approaching pairs,
  a_i = sum_j m_j alpha c0 mu_ij / rho * grad_i W_ij,   mu_ij = h v_ij.x_ij / (r^2 + 0.01 h^2)   (v_ij.x_ij < 0),
and the stress on the wall is rho times the sum over the fluid rows of dp a_i. The script prints that stress
over rho alpha c0 v for several dp: it has no dp in it, which is why refining at a fixed alpha leaves the
dam break's no-slip hold as it is (docs/validation.md, "Dam break: the column's height at the back wall").
usage: /usr/bin/python3 docs/validation/av_wall_stress.py
"""
import math

from vonneumann import grad_factor  # W'(r) / r of the code's kernels, next to this file


def wall_stress_coefficient(dp, h_over_dp=1.5, wall_layers=3):
    """Stress / (rho alpha c0 v) on the fluid, summed over every fluid row the wall reaches."""
    h = h_over_dp * dp
    v = 1.0  # alpha = c0 = rho = v = 1: the result is the coefficient itself
    reach = int(math.ceil(2.0 * h / dp))
    stress = 0.0
    for row in range(reach + 1):
        yi = (row + 0.5) * dp
        ax = 0.0
        for layer in range(wall_layers):
            yj = -(layer + 0.5) * dp
            for k in range(-reach, reach + 1):
                dx, dy = -k * dp, yi - yj          # x_i - x_j
                r = math.hypot(dx, dy)
                vdotx = 2.0 * v * dx               # v_ij = v - (-v)
                if r >= 2.0 * h or vdotx >= 0.0:
                    continue
                mu = h * vdotx / (r * r + 0.01 * h * h)
                ax += dp * dp * mu * dx * float(grad_factor("wendland", r, h))   # m_j / rho = dp^2
        stress += dp * ax
    return -stress  # the wall drags the fluid back: report the magnitude


if __name__ == "__main__":
    for n in (10, 20, 40, 80, 160):
        dp = 0.1 / n
        print(f"dp = a/{n:<3d}  stress / (rho alpha c0 v) = {wall_stress_coefficient(dp):.4f}")
