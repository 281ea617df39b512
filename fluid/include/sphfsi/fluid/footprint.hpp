#pragma once
// What a [fluid] section will cost in memory before anything is allocated, so that a spacing too fine for
// the machine is refused by the scene check, naming fluid.dp, instead of ending in std::bad_alloc (or the
// kernel's out-of-memory killer) minutes into setting up the lattice.
#include "sphfsi/protocol/value.hpp"

namespace sphfsi::fluid {

// Peak resident bytes per particle of a run on one machine, rounded up: the solver's arrays are 160 - 172 B;
// the participant with its FRAME messages peaks at 394 B and the coordinator recording them at 180 - 190 B,
// 574 - 584 B together (tools/run_memory.py, docs/benchmarks.md "Memory of a whole run").
constexpr double kBytesPerParticle = 600.0;
// PCISPH also lists each particle's pairs once a step (gradient_pairs.hpp): 12 B a pair, 28 B on a periodic
// grid, with 1/16 head room, and an 8-byte start per particle. The estimate counts a full neighbourhood,
// pi (support / dp)^2 pairs (2D), for every particle: walls have none, so this is an upper bound.
double pair_list_bytes_per_particle(double support_over_dp, bool periodic);
// The neighbour grid holds one 4-byte cell start per cell of one support radius.
constexpr double kBytesPerCell = 4.0;
// Particle ids are signed 32-bit (ParticleStore::id, the first solid's id).
constexpr double kMaxParticles = 2147483647.0;

struct Footprint {
    double particles = 0;  // fluid, tank walls, obstacles and gate, as the lattice lays them out
    double wall_particles = 0;  // of which the tank's walls
    double cells = 0;      // neighbour-grid cells over the tank, its walls and the head room above an open top
    double bytes_per_particle = kBytesPerParticle;  // plus PCISPH's pair list
    double bytes() const { return particles * bytes_per_particle + cells * kBytesPerCell; }
};

// From a section with its defaults filled in (with_defaults). Counts in doubles, so absurd spacings do
// not overflow.
Footprint estimate_footprint(const sphfsi::Value& fluid);

// This machine's physical memory [bytes] (0 if unknown).
double physical_memory_bytes();

}  // namespace sphfsi::fluid
