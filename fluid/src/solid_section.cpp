#include "sphfsi/fluid/solid_section.hpp"

#include <algorithm>
#include <map>
#include <utility>

namespace sphfsi::fluid {
namespace {

// Signed distance of p from the line through a and b, positive on its left (inside a counter-clockwise cell).
double inside_distance(const Vec2& a, const Vec2& b, const Vec2& p) {
    const Vec2 e = b - a;
    const double len = norm(e);
    return len > 0.0 ? (e[0] * (p[1] - a[1]) - e[1] * (p[0] - a[0])) / len : 0.0;
}

}  // namespace

SolidSection::SolidSection(std::vector<std::array<std::int32_t, 4>> cells, Vertices vertices, double layers, double dp)
    : cells_(std::move(cells)), vertices_(std::move(vertices)), layers_(layers), dp_(dp) {
    // An edge two cells share is inside the structure; the others are its faces.
    std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
    for (const auto& c : cells_)
        for (int k = 0; k < 4; ++k) ++uses[std::minmax(c[static_cast<std::size_t>(k)], c[static_cast<std::size_t>((k + 1) % 4)])];
    face_.resize(cells_.size());
    for (std::size_t i = 0; i < cells_.size(); ++i)
        for (int k = 0; k < 4; ++k)
            face_[i][static_cast<std::size_t>(k)] =
                uses[std::minmax(cells_[i][static_cast<std::size_t>(k)], cells_[i][static_cast<std::size_t>((k + 1) % 4)])] == 1;
}

void SolidSection::place(double t) {
    vertices_(t, at_);
    lo_ = hi_ = at_.empty() ? Vec2{} : at_.front();
    for (const Vec2& v : at_)
        for (int k = 0; k < 2; ++k) {
            lo_[k] = std::min(lo_[k], v[k]);
            hi_[k] = std::max(hi_[k], v[k]);
        }
}

bool SolidSection::lost(const Vec2& x) const {
    if (x[0] < lo_[0] || x[0] > hi_[0] || x[1] < lo_[1] || x[1] > hi_[1]) return false;
    for (std::size_t i = 0; i < cells_.size(); ++i) {
        std::array<Vec2, 4> q;
        for (int k = 0; k < 4; ++k) q[static_cast<std::size_t>(k)] = at_[static_cast<std::size_t>(cells_[i][static_cast<std::size_t>(k)])];
        // Inside the cell, and how far from its faces; its extent across each face bounds the section's
        // thickness there (a beam cell: its thickness from a long face, its length from an end face).
        double depth = 0.0, across = 0.0;
        bool inside = true, has_face = false;
        for (int k = 0; k < 4 && inside; ++k) {
            const Vec2 &a = q[static_cast<std::size_t>(k)], &b = q[static_cast<std::size_t>((k + 1) % 4)];
            const double d = inside_distance(a, b, x);
            inside = d >= 0.0;
            if (!face_[i][static_cast<std::size_t>(k)]) continue;
            double extent = 0.0;
            for (const Vec2& v : q) extent = std::max(extent, inside_distance(a, b, v));
            depth = has_face ? std::min(depth, d) : d;
            across = has_face ? std::min(across, extent) : extent;
            has_face = true;
        }
        if (!inside || !has_face) continue;  // outside, or a cell with no face (deep in a thick section)
        const double allowed = std::min(layers_, std::max(0.5 * (across - dp_), 0.5 * dp_));
        if (depth > allowed) return true;
    }
    return false;
}

}  // namespace sphfsi::fluid
