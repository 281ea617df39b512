#pragma once
// What the neighbour grid (cell_grid.hpp) can hold, in one place, so that the scene check refuses what the
// grid would refuse, by the same arithmetic, naming the key, instead of the grid failing at INIT.
#include <cmath>

namespace sphfsi::fluid {

// Cells are a hair wider than the support radius, so that rounding in the binning can never separate a true
// pair by two cells (cell_grid.hpp, "Exactness").
inline constexpr double kCellOverSupport = 1.0 + 1e-12;

// The cells along a periodic axis of length `len`: whole cells of at least that width. The grid needs 3.
inline double periodic_cells(double len, double support) { return std::floor(len / (support * kCellOverSupport)); }

// Cell indices are 32-bit, and the grid numbers 3 buckets past its last cell (particles outside it, and the
// two ends of its ranges): more cells than this would wrap and bin particles into the wrong cells.
inline constexpr double kMaxCells = 4294967295.0 - 3.0;

}  // namespace sphfsi::fluid
