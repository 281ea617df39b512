#pragma once
// Scene sections for the structure tests, built as the Value a scene file would parse to, so every
// test goes through the real schema and config path.
#include <cmath>
#include <string>

#include "sphfsi/protocol/value.hpp"
#include "sphfsi/structure/config.hpp"

namespace structure_test {

using sphfsi::Value;

inline Value vec(double x, double y) { return Value(Value::Array{Value(x), Value(y)}); }
inline Value table(Value::Table t) { return Value(std::move(t)); }

// Steel strip: L = 1 m, t = 10 mm, b = 1 m => EI = E t^3 / 12 = 17500 N m^2, rho A = 78.5 kg/m.
constexpr double E = 2.1e11, rho = 7850.0, t = 0.01, L = 1.0;
constexpr double EI = E * t * t * t / 12.0, rhoA = rho * t;

// A horizontal member from (0,0) to (L,0) with `n` elements; supports at the ends as given ("" = none).
inline Value beam(int n, const std::string& left = "clamped", const std::string& right = "",
                  const std::string& formulation = "linear") {
    Value::Array supports;
    if (!left.empty()) supports.push_back(table({{"at", vec(0, 0)}, {"type", Value(left)}}));
    if (!right.empty()) supports.push_back(table({{"at", vec(L, 0)}, {"type", Value(right)}}));
    return table({
        {"formulation", Value(formulation)},
        {"material", table({{"E", Value(E)}, {"rho", Value(rho)}})},
        {"section", table({{"thickness", Value(t)}})},
        {"members", Value(Value::Array{table({{"start", vec(0, 0)}, {"end", vec(L, 0)}, {"n_elements", Value(n)}})})},
        {"supports", Value(std::move(supports))},
    });
}

inline void set(Value& scene, const std::string& path, Value v) { sphfsi::set_path(scene, path, std::move(v)); }

inline Value point_load(double x, double y, double fx, double fy, double moment = 0.0) {
    return table({{"at", vec(x, y)}, {"force", vec(fx, fy)}, {"moment", Value(moment)}});
}

inline sphfsi::structure::StructureConfig config(const Value& scene) {
    return sphfsi::structure::StructureConfig::from_value(scene);
}

inline double rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

}  // namespace structure_test
