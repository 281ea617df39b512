#include "sphfsi/fluid/solid_section.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace sphfsi::fluid {
namespace {

double cross(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }

// Crossing-number test: inside a quadrilateral of either turning, convex or not.
bool inside_quad(const std::array<Vec2, 4>& q, const Vec2& x) {
    bool in = false;
    for (std::size_t k = 0, j = 3; k < 4; j = k++) {
        const Vec2 &a = q[k], &b = q[j];
        if ((a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (b[0] - a[0]) * (x[1] - a[1]) / (b[1] - a[1])) in = !in;
    }
    return in;
}

// Nearest point of segment a-b to x, and where along it (u in [0, 1] when x lies over the segment).
Vec2 foot_on(const Vec2& a, const Vec2& b, const Vec2& x, double& u) {
    const Vec2 e = b - a;
    const double len2 = dot(e, e);
    u = len2 > 0.0 ? dot(x - a, e) / len2 : 0.0;
    return a + e * std::clamp(u, 0.0, 1.0);
}

// How far past a boundary point the union is probed to see whether it goes on (1e-6 dp: far above the
// round-off of coordinates of a few metres, far below anything a particle resolves).
double probe_step(double dp) { return 1e-6 * dp; }

}  // namespace

SolidSection::SolidSection(std::string name, std::vector<Quad> cells, const std::vector<Vec2>& reference,
                           Vertices vertices, Touchable touchable, double layers, double dp)
    : name_(std::move(name)), cells_(std::move(cells)), vertices_(std::move(vertices)),
      touchable_(std::move(touchable)), layers_(layers), dp_(dp) {
    // Vertices at the same reference place (to 1e-6 dp) are one, so cells that repeat a vertex instead of
    // sharing its index still share the edge.
    const double tol = 1e-6 * dp;
    std::map<std::pair<long long, long long>, std::int32_t> by_place;
    std::vector<std::int32_t> same(reference.size());
    for (std::size_t v = 0; v < reference.size(); ++v) {
        const auto key = std::make_pair(std::llround(reference[v][0] / tol), std::llround(reference[v][1] / tol));
        same[v] = by_place.emplace(key, static_cast<std::int32_t>(v)).first->second;
    }
    std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
    auto edge = [&](const Quad& c, std::size_t k) {
        return std::minmax(same[static_cast<std::size_t>(c[k])], same[static_cast<std::size_t>(c[(k + 1) % 4])]);
    };
    for (const Quad& c : cells_)
        for (std::size_t k = 0; k < 4; ++k) ++uses[edge(c, k)];
    face_edges_.assign(cells_.size(), 0);
    for (std::size_t i = 0; i < cells_.size(); ++i)
        for (std::size_t k = 0; k < 4; ++k) {
            const Quad& c = cells_[i];
            const auto e = edge(c, k);
            const bool point = e.first == e.second;
            if (!point && uses[e] != 1) continue;
            if (!point) faces_.push_back({c[k], c[(k + 1) % 4]});
            face_edges_[i] = static_cast<std::uint8_t>(face_edges_[i] | (1u << k));
        }
    for (std::uint8_t f : face_edges_) any_middle_ = any_middle_ || (f & 0b0101) == 0b0101 || (f & 0b1010) == 0b1010;
}

template <class Box>
void SolidSection::fill(Bins& bins, std::size_t n, const Box& box_of) {
    bins.start.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) + 1, 0);
    auto each_bin = [&](std::size_t i, auto&& visit) {
        Vec2 lo, hi;
        box_of(i, lo, hi);
        const auto a = bin_of(lo), b = bin_of(hi);
        for (int y = a[1]; y <= b[1]; ++y)
            for (int x = a[0]; x <= b[0]; ++x) visit(static_cast<std::size_t>(y) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(x));
    };
    for (std::size_t i = 0; i < n; ++i) each_bin(i, [&](std::size_t k) { ++bins.start[k + 1]; });
    for (std::size_t k = 1; k < bins.start.size(); ++k) bins.start[k] += bins.start[k - 1];
    bins.items.resize(bins.start.back());
    std::vector<std::uint32_t> next(bins.start.begin(), bins.start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) each_bin(i, [&](std::size_t k) { bins.items[next[k]++] = static_cast<std::uint32_t>(i); });
}

void SolidSection::place(double t, double dt) {
    vertices_(t, at_);
    if (any_middle_ && dt > 0.0) vertices_(t - dt, before_);
    else before_ = at_;
    lo_ = hi_ = at_.empty() ? Vec2{} : at_.front();
    for (const Vec2& v : at_)
        for (int k = 0; k < 2; ++k) {
            lo_[k] = std::min(lo_[k], v[k]);
            hi_[k] = std::max(hi_[k], v[k]);
        }
    placed_faces_.clear();
    for (const auto& f : faces_) placed_faces_.push_back({at_[static_cast<std::size_t>(f[0])], at_[static_cast<std::size_t>(f[1])]});
    // Bins a quarter of the farthest a face can matter (2 L + dp) wide, wider where the section is so large
    // that those would number more than 2^20 (counted in doubles: a vertex flung 1e8 m away must not overflow).
    bin_ = 0.25 * reach();
    double nx = 1.0, ny = 1.0;
    for (;;) {
        nx = std::floor((hi_[0] - lo_[0]) / bin_) + 1.0;
        ny = std::floor((hi_[1] - lo_[1]) / bin_) + 1.0;
        if (!(nx * ny > double(1 << 20))) break;  // also leaves the loop on a non-finite extent
        bin_ *= 2.0;
    }
    if (!std::isfinite(nx * ny)) nx = ny = 1.0, bin_ = std::numeric_limits<double>::infinity();
    nx_ = static_cast<int>(nx), ny_ = static_cast<int>(ny);
    reach_ = std::max(1, static_cast<int>(std::ceil(reach() / bin_)));
    fill(cell_bins_, cells_.size(), [&](std::size_t i, Vec2& lo, Vec2& hi) {
        lo = hi = at_[static_cast<std::size_t>(cells_[i][0])];
        for (std::int32_t v : cells_[i])
            for (int k = 0; k < 2; ++k) {
                lo[k] = std::min(lo[k], at_[static_cast<std::size_t>(v)][k]);
                hi[k] = std::max(hi[k], at_[static_cast<std::size_t>(v)][k]);
            }
    });
    fill(face_bins_, placed_faces_.size(), [&](std::size_t i, Vec2& lo, Vec2& hi) {
        const Face& f = placed_faces_[i];
        for (int k = 0; k < 2; ++k) {
            lo[k] = std::min(f.a[k], f.b[k]);
            hi[k] = std::max(f.a[k], f.b[k]);
        }
    });
}

std::array<int, 2> SolidSection::bin_of(const Vec2& x) const {
    auto along = [&](int k, int n) {
        const double b = std::floor((x[k] - lo_[k]) / bin_);
        return b < 0.0 ? 0 : b >= n - 1 ? n - 1 : static_cast<int>(b);  // clamped before the cast
    };
    return {along(0, nx_), along(1, ny_)};
}

bool SolidSection::inside(const Vec2& x) const {
    // Written so that a NaN coordinate is outside; not placed yet: nothing is inside.
    if (nx_ == 0 || !(x[0] >= lo_[0] && x[0] <= hi_[0] && x[1] >= lo_[1] && x[1] <= hi_[1])) return false;
    const auto b = bin_of(x);
    const std::size_t k = static_cast<std::size_t>(b[1]) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(b[0]);
    for (std::uint32_t i = cell_bins_.start[k]; i < cell_bins_.start[k + 1]; ++i) {
        const Quad& c = cells_[cell_bins_.items[i]];
        std::array<Vec2, 4> q;
        for (std::size_t v = 0; v < 4; ++v) q[v] = at_[static_cast<std::size_t>(c[v])];
        if (inside_quad(q, x)) return true;
    }
    return false;
}

// A face's point is the solid's surface when the union does not go on just beyond it (an overlapped face at
// a joint of two members is not), and water can touch it when it is inside the tank.
bool SolidSection::surface_at(const Vec2& foot, const Vec2& inward) const {
    return !inside(foot - inward * probe_step(dp_)) && (!touchable_ || touchable_(foot));
}

// Whether the centre x, `depth` below a surface point `foot`, is within what that face allows: the thickness
// is measured on along the line from the foot through x to where the union ends.
bool SolidSection::at_a_face(const Vec2& x, const Vec2& foot, double depth, const std::vector<std::uint32_t>& near) const {
    const Vec2 n = (x - foot) * (1.0 / depth);
    thread_local std::vector<double> hits;
    hits.clear();
    for (std::uint32_t i : near) {
        const Face& f = placed_faces_[i];
        const Vec2 e = f.b - f.a, r = f.a - x;
        const double denom = cross(n, e);
        if (denom == 0.0) continue;  // along the line: it meets the line's ends' faces instead
        const double s = cross(r, e) / denom, w = cross(r, n) / denom;
        if (s > 0.0 && s < reach() && w >= 0.0 && w <= 1.0) hits.push_back(s);  // beyond, the allowance is L
    }
    std::sort(hits.begin(), hits.end());
    double beyond = std::numeric_limits<double>::infinity();
    for (double s : hits)
        if (!inside(x + n * (s + probe_step(dp_)))) {  // the union ends here, not just an overlapped face
            beyond = s;
            break;
        }
    const double across = depth + beyond;
    const double allowed = std::min(layers_, std::max(0.5 * (across - dp_), 0.5 * dp_));
    return depth <= allowed;
}

// The faces binned within `bins` bins of x's, in a scratch list of the calling thread: lost() runs inside
// the parallel check, for every centre inside the section, every step.
const std::vector<std::uint32_t>& SolidSection::faces_near(const Vec2& x, int bins) const {
    thread_local std::vector<std::uint32_t> near;
    const auto b = bin_of(x);
    gather(face_bins_, {b[0] - bins, b[1] - bins}, {b[0] + bins, b[1] + bins}, near);
    return near;
}

// The items of the bins from b0 to b1 (corners included, clamped to the grid), each once, into `out`.
void SolidSection::gather(const Bins& bins, std::array<int, 2> b0, std::array<int, 2> b1, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (int y = std::max(b0[1], 0); y <= std::min(b1[1], ny_ - 1); ++y)
        for (int x = std::max(b0[0], 0); x <= std::min(b1[0], nx_ - 1); ++x) {
            const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(x);
            out.insert(out.end(), bins.items.begin() + bins.start[k], bins.items.begin() + bins.start[k + 1]);
        }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

// Whether a surface point lies within `tol` of x (on a face counts), from the faces of the 3 x 3 bins around
// it: bins are at least a quarter of 2 L + dp wide, more than the dp/2 and 0.1 dp asked for.
bool SolidSection::surface_within(const Vec2& x, double tol) const {
    for (std::uint32_t i : faces_near(x, 1)) {
        const Face& f = placed_faces_[i];
        double u = 0.0;
        const Vec2 foot = foot_on(f.a, f.b, x, u);
        const double depth = norm(x - foot);
        if (depth == 0.0) return true;
        if (depth <= tol && surface_at(foot, (x - foot) * (1.0 / depth))) return true;
    }
    return false;
}

bool SolidSection::past_surface(const Vec2& x, double tol) const { return inside(x) && !surface_within(x, tol); }

bool SolidSection::crossed_middle(const Vec2& from, const Vec2& to) const {
    if (!any_middle_ || nx_ == 0) return false;
    // The cells binned around the path, grown by a bin: within a step a cell moves far less than a bin (a
    // quarter of 2 L + dp). Written so that a non-finite position crosses nothing (check_state names it).
    Vec2 lo{}, hi{};
    for (int k = 0; k < 2; ++k) {
        lo[k] = std::min(from[k], to[k]) - bin_;
        hi[k] = std::max(from[k], to[k]) + bin_;
        if (!(hi[k] >= lo_[k] && lo[k] <= hi_[k])) return false;
    }
    thread_local std::vector<std::uint32_t> near;
    gather(cell_bins_, bin_of(lo), bin_of(hi), near);
    for (std::uint32_t i : near) {
        const Quad& c = cells_[i];
        const unsigned faces = face_edges_[i];
        auto mid = [&](const std::vector<Vec2>& v, unsigned e) {
            return (v[static_cast<std::size_t>(c[e])] + v[static_cast<std::size_t>(c[(e + 1) % 4])]) * 0.5;
        };
        for (unsigned k = 0; k < 2; ++k) {
            if (!(faces & (1u << k)) || !(faces & (1u << (k + 2)))) continue;
            const unsigned ea = (k + 3) % 4, eb = k + 1;  // the middle line runs between these edges
            const Vec2 a0 = mid(before_, ea), b0m = mid(before_, eb), a1 = mid(at_, ea), b1m = mid(at_, eb);
            // Which side of the middle the centre is on at each end of the step, each against the middle then.
            const double f0 = cross(b0m - a0, from - a0), f1 = cross(b1m - a1, to - a1);
            if (!((f0 < 0.0 && f1 > 0.0) || (f0 > 0.0 && f1 < 0.0))) continue;
            const double s = f0 / (f0 - f1);  // where along the step, the middle moving linearly with it
            const Vec2 a = a0 + (a1 - a0) * s, e = b0m + (b1m - b0m) * s - a, p = from + (to - from) * s;
            const double len = norm(e);
            if (len == 0.0) continue;
            const double along = dot(p - a, e) / len;
            // Half a spacing's margin at an end that is a face the water can touch (a free end, or one drawn to a
            // point).
            auto margin = [&](unsigned edge, const Vec2& at) {
                return (faces & (1u << edge)) && (!touchable_ || touchable_(at)) ? 0.5 * dp_ : 0.0;
            };
            if (along >= margin(ea, a1) && along <= len - margin(eb, b1m)) return true;
        }
    }
    return false;
}

bool SolidSection::lost(const Vec2& x) const {
    // A centre no deeper than dp/2 below a surface point is at a face whatever the thickness (the allowance
    // is at least dp/2). That settles the common case, a centre just past a face, with one probe.
    if (!inside(x) || surface_within(x, 0.5 * dp_)) return false;
    constexpr double over = 1e-9;  // a centre over a shared corner lies over both faces
    // Deeper: the face points within L, nearest first, each measured across the section.
    const std::vector<std::uint32_t>& near = faces_near(x, reach_);
    struct Candidate {
        double depth;
        Vec2 foot;
        bool over_face;  // x lies over the face (else its nearest point on it is a corner)
    };
    thread_local std::vector<Candidate> candidates;
    candidates.clear();
    for (std::uint32_t i : near) {
        const Face& f = placed_faces_[i];
        double u = 0.0;
        const Vec2 foot = foot_on(f.a, f.b, x, u);
        const double depth = norm(x - foot);
        if (depth <= layers_) candidates.push_back({depth, foot, u >= -over && u <= 1.0 + over});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.depth < b.depth; });
    bool nearest = true;
    for (const Candidate& c : candidates) {
        if (!surface_at(c.foot, (x - c.foot) * (1.0 / c.depth))) continue;
        // A centre over no face near it (beside a corner that turns into the solid) is measured from that
        // corner, when it is the nearest surface point.
        if ((c.over_face || nearest) && at_a_face(x, c.foot, c.depth, near)) return false;
        nearest = false;
    }
    return true;
}

}  // namespace sphfsi::fluid
