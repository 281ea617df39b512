#pragma once
// Scene sections ([fluid] tables) used by the fluid tests, written the way a scene file would be.
#include <string>
#include <utility>
#include <vector>

#include "sphfsi/protocol/value.hpp"

namespace fluid_test {

using sphfsi::Value;

// Sets dotted keys on a table: with(base, {{"pressure.model", "pcisph"}, ...}).
inline Value with(Value base, const std::vector<std::pair<std::string, Value>>& keys) {
    for (const auto& [k, v] : keys) sphfsi::set_path(base, k, v);
    return base;
}

// An axis-aligned box [x0, x0 + w] x [y0, y0 + h]: an [[obstacle]] as it stands.
inline Value box(double x0, double y0, double w, double h) {
    Value::Table t;
    t["x0"] = x0;
    t["y0"] = y0;
    t["width"] = w;
    t["height"] = h;
    return Value(std::move(t));
}

// A [[water]] block: a box with its dye tag and how the dye splits it.
inline Value block(double x0, double y0, double w, double h, int tag = 0, const char* split = "none") {
    Value b = box(x0, y0, w, h);
    b.as_table_mut()["tag"] = tag;
    b.as_table_mut()["split"] = split;
    return b;
}

inline Value vec2(double a, double b) { return Value(Value::Array{Value(a), Value(b)}); }

// A tank `width` x `height` at spacing dp holding one undyed block of water `water_width` x `water_height`
// in its lower left corner; everything else at the scene defaults.
inline Value water_tank(double dp, double width, double height, double water_width, double water_height) {
    Value f;
    f.make_table();
    f = with(f, {{"dp", dp}, {"tank.width", width}, {"tank.height", height}});
    f.as_table_mut()["water"] = Value(Value::Array{block(0.0, 0.0, water_width, water_height)});
    return f;
}

// The thesis's dam break: a column 0.1 m wide and 0.2 m high against the left wall of a tank, dyed in
// two halves. Martin & Moyce's (1952) n^2 = 2 column has the same aspect ratio.
inline Value dam_break(double dp) {
    Value f;
    f.make_table();
    f = with(f, {{"dp", dp}, {"tank.width", 0.5}, {"tank.height", 0.3}, {"kernel", "wendland"}, {"h_over_dp", 1.5}});
    f.as_table_mut()["water"] = Value(Value::Array{block(0.0, 0.0, 0.1, 0.2, 0, "vertical")});
    return f;
}

// WCSPH with the options the field uses for a dam break (DualSPHysics-like): Tait, continuity with
// Fourtakas density diffusion, artificial viscosity, Adami walls.
inline Value wcsph(Value f) {
    return with(std::move(f), {{"pressure.model", "wcsph"},
                               {"density.method", "continuity"},
                               {"density.diffusion", "fourtakas"},
                               {"viscosity.model", "artificial"},
                               {"viscosity.alpha", 0.02},
                               {"boundary.model", "adami"}});
}

inline Value pcisph(Value f) {
    return with(std::move(f), {{"pressure.model", "pcisph"},
                               {"density.method", "summation"},
                               {"viscosity.model", "artificial"},
                               {"viscosity.alpha", 0.02},
                               {"boundary.model", "adami"}});
}

}  // namespace fluid_test
