#pragma once
// A number in a scene error message, as short as the stream writes it (1e-300, not 300 digits).
#include <sstream>
#include <string>

namespace sphfsi::coordinator {

inline std::string shortest(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
}

}  // namespace sphfsi::coordinator
