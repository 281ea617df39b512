#include "sphfsi/protocol/mapping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sphfsi::protocol {
namespace {
constexpr double kSign[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};  // reference corners, CCW

std::array<double, 4> shape(double xi, double eta) {
    std::array<double, 4> n{};
    for (int i = 0; i < 4; ++i) n[i] = 0.25 * (1 + kSign[i][0] * xi) * (1 + kSign[i][1] * eta);
    return n;
}
}  // namespace

std::array<double, 4> bilinear_weights(const std::array<std::array<double, 2>, 4>& q, double x, double y,
                                       double* outside_distance) {
    double xi = 0, eta = 0;
    for (int it = 0; it < 30; ++it) {
        auto n = shape(xi, eta);
        double fx = -x, fy = -y, j11 = 0, j12 = 0, j21 = 0, j22 = 0;
        for (int i = 0; i < 4; ++i) {
            fx += n[i] * q[i][0];
            fy += n[i] * q[i][1];
            double dxi = 0.25 * kSign[i][0] * (1 + kSign[i][1] * eta), deta = 0.25 * kSign[i][1] * (1 + kSign[i][0] * xi);
            j11 += dxi * q[i][0];
            j12 += deta * q[i][0];
            j21 += dxi * q[i][1];
            j22 += deta * q[i][1];
        }
        double det = j11 * j22 - j12 * j21;
        if (std::abs(det) < 1e-300) break;
        double dxi = (j22 * fx - j12 * fy) / det, deta = (-j21 * fx + j11 * fy) / det;
        xi -= dxi;
        eta -= deta;
        if (std::abs(dxi) + std::abs(deta) < 1e-14) break;
    }
    // Far from the origin (a cell at 1e300 m) the iteration overflows to NaN, which clamp passes through: the
    // cell's centre stands in, so the weights stay weights and the distance is still from the cell.
    if (!std::isfinite(xi) || !std::isfinite(eta)) xi = eta = 0.0;
    double cxi = std::clamp(xi, -1.0, 1.0), ceta = std::clamp(eta, -1.0, 1.0);
    auto n = shape(cxi, ceta);
    if (outside_distance) {
        double px = 0, py = 0;
        for (int i = 0; i < 4; ++i) {
            px += n[i] * q[i][0];
            py += n[i] * q[i][1];
        }
        const double d = std::hypot(px - x, py - y);
        *outside_distance = std::isnan(d) ? std::numeric_limits<double>::infinity() : d;  // never nearer than it is
    }
    return n;
}

MappedPoint locate(const InterfaceMesh& mesh, double x, double y) {
    MappedPoint best;
    best.distance = std::numeric_limits<double>::infinity();
    for (std::uint64_t c = 0; c < mesh.cells.rows(); ++c) {
        std::array<std::array<double, 2>, 4> q{};
        std::array<std::int32_t, 4> idx{};
        for (int i = 0; i < 4; ++i) {
            idx[i] = mesh.cells(c, i);
            q[i] = {mesh.vertices(idx[i], 0), mesh.vertices(idx[i], 1)};
        }
        double d = 0;
        auto w = bilinear_weights(q, x, y, &d);
        if (best.cell < 0 || d < best.distance) {  // the first cell even at an infinite distance
            best = MappedPoint{static_cast<std::int32_t>(c), idx, w, d};
            if (d < 1e-12) break;
        }
    }
    return best;
}

std::array<double, 2> interpolate(const MappedPoint& p, const F64Array& f) {
    std::array<double, 2> out{0, 0};
    for (int i = 0; i < 4; ++i) {
        out[0] += p.weight[i] * f(p.vertex[i], 0);
        out[1] += p.weight[i] * f(p.vertex[i], 1);
    }
    return out;
}

void spread(const MappedPoint& p, const std::array<double, 2>& force, F64Array& vf) {
    for (int i = 0; i < 4; ++i) {
        vf(p.vertex[i], 0) += p.weight[i] * force[0];
        vf(p.vertex[i], 1) += p.weight[i] * force[1];
    }
}

}  // namespace sphfsi::protocol
