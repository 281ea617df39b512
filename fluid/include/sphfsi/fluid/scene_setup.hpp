#pragma once
// Builds the initial particle set of a 2D scene: water blocks on a dp lattice, the tank's wall particles
// (several layers; none across a periodic axis; a lid when the top is closed) and static obstacle boxes.
// Fluid particles come first in id order, then walls; solid particles (coupling) are appended later.
#include <vector>

#include "sphfsi/fluid/particles.hpp"
#include "sphfsi/fluid/settings.hpp"

namespace sphfsi::fluid {

// Where fluid may not go, for the failure check ("lost through a wall") and the validation check (no
// particle centre beyond a wall surface).
struct WallGeometry {
    double width = 0, height = 0;      // tank interior [0, width] x [0, height]
    double thickness = 0;              // wall_layers * dp
    bool walls_x = true, floor = true, lid = false;  // which tank walls exist
    std::vector<Box> obstacles;
};

struct Scene2D {
    ParticleStore<2> particles;
    std::size_t n_fluid = 0, n_wall = 0;
    WallGeometry geometry;
    Vec2 domain_lo{}, domain_hi{};     // region gridded for the neighbour search (periodic axes: one period)
    std::vector<double> column_top;    // per fluid particle: top of its block (hydrostatic initial density)
};

Scene2D build_scene(const FluidSettings& s);

// Whether p is inside the tank's interior, off its wall surfaces (by 1e-9 of the tank's size): where water can
// touch a solid's face.
bool inside_tank(const WallGeometry& g, const Vec2& p);

}  // namespace sphfsi::fluid
