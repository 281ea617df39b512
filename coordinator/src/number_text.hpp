#pragma once
// A number in a scene error message, as short as the stream writes it (1e-300, not 300 digits).
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace sphfsi::coordinator {

// Six significant digits where they are the number itself, else every digit it takes to read it back (a
// position 1e-7 outside the tank must not print as on its edge).
inline std::string shortest(double x) {
    std::ostringstream s;
    s << x;
    if (std::strtod(s.str().c_str(), nullptr) == x || !std::isfinite(x)) return s.str();
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    return std::string(buf, r.ptr);
}

}  // namespace sphfsi::coordinator
