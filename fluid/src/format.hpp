#pragma once
// Numbers in failure messages: six significant digits, as printf's %g.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sphfsi::fluid {

inline std::string fmt(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
}

// Numbers in scene errors: six significant digits where they are the number itself, else every digit it takes
// to read it back (a box 1e-7 m outside the tank printed as [-0.000000, ...], inside it; a review, 2026-11-28).
inline std::string exact(double x) {
    std::string s = fmt(x);
    if (std::strtod(s.c_str(), nullptr) == x || !std::isfinite(x)) return s;
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    return std::string(buf, r.ptr);
}

}  // namespace sphfsi::fluid
