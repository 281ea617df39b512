#pragma once
// The prototype neighbourhood of a particle inside a freshly laid-out block: the nodes of the square (2D)
// or cubic (3D) lattice of spacing dp within a radius of the origin. Solver constants derived from the
// initial state (PCISPH's stiffness, the kinematic density's normalisation) sum over it.
#include <cmath>

#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

// Calls f(dx, r) for every lattice offset dx with 0 < r = |dx| < radius (the origin excluded).
template <int Dim, class F>
void for_each_lattice_neighbour(double dp, double radius, F&& f) {
    const int n = static_cast<int>(std::ceil(radius / dp)) + 1;
    int idx[3] = {-n, -n, -n};
    while (true) {
        Vec<Dim> dx{};
        for (int k = 0; k < Dim; ++k) dx[k] = idx[k] * dp;
        const double r2 = norm2(dx);
        if (r2 > 0.0 && r2 < radius * radius) f(dx, std::sqrt(r2));
        int k = 0;
        while (k < Dim && ++idx[k] > n) idx[k++] = -n;
        if (k == Dim) break;
    }
}

}  // namespace sphfsi::fluid
