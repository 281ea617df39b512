#pragma once
// Numbers in failure messages: six significant digits, as printf's %g.
#include <cstdio>
#include <string>

namespace sphfsi::fluid {

inline std::string fmt(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
}

}  // namespace sphfsi::fluid
