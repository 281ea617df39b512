#pragma once
// A lifted gate (scene table [fluid.gate]): a vertical box of solid particles standing on the floor that
// holds the water until t = 0 and from then on rises at a constant speed, until its bottom edge is as high
// as its top edge was (it then stops, clear of its own starting span and inside the neighbour grid).
//
// Why. An experiment does not remove its gate at once. A constant speed is the simplest motion with a
// stated time scale (a measured lifting profile, as some experiments give, would be a table of offsets;
// not built, as no scene here has one). It also tests an explanation: simulations released
// at once lead Martin & Moyce's (1952) front by an almost constant time, commonly put down to their gate.
// Lifted at any constant speed from 0.5 to 8 m/s, with any of the three pressure models, this gate does not
// delay the front: water runs out under it and leads the experiment further at T <= 1.2 (docs/validation.md,
// "Dam break"; sweeps/dam_break_gate.toml). The water leaving under it is still accelerating 30 ms after the
// gap opens (0.7 - 0.9 m/s at a 2 m/s gate, every model, against Torricelli's 2 m/s for a steady outflow).
// The gate is an option no scene turns on.
//
// The gate's particles are solid particles like those of a coupled structure (Adami wall pressure with the
// gate's own velocity; no-slip as for the walls), driven by this prescribed motion instead of a structure.
// Fluid through it stops the run as fluid through a coupled structure does (solid_section.hpp).
#include <vector>

#include "sphfsi/fluid/settings.hpp"
#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

// Particle centres of the gate at t = 0 on the dp lattice of its box [x0, x0 + thickness] x [0, height].
std::vector<Vec<2>> gate_particles(const FluidSettings& s);

// The gate's rise at time t (t0 = 0): offset and velocity along +y (no acceleration: it starts and stops at
// once, moving along its own faces). At t = 0 itself the gate already moves: the forces of the first step
// are evaluated at its start, and that step is the first of the rise, so its walls must carry the speed.
struct GateLift {
    double speed = 0.0, travel = 0.0;
    void at(double t, double& offset, double& velocity) const {
        const double t_stop = travel / speed;
        if (t < 0.0) {
            offset = 0.0, velocity = 0.0;
        } else if (t < t_stop) {
            offset = speed * t, velocity = speed;
        } else {
            offset = travel, velocity = 0.0;
        }
    }
};

}  // namespace sphfsi::fluid
