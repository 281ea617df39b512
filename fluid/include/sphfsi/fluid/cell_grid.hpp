#pragma once
// Cell-linked-list neighbour search. Particles are binned into cells at least one support radius wide and
// reordered by cell with a stable counting sort, so that each cell's particles are contiguous in memory.
// Cells are numbered with axis 0 fastest, so the three cells (k0-1, k0, k0+1) of one row are one
// contiguous index range: a particle's candidates are 3^(Dim-1) ranges, not 3^Dim cells. Periodic axes
// wrap; a range reached across the wrap carries the shift to add to the neighbour's position.
//
// Exactness: a pair closer than the radius lies in adjacent cells because the cell size is a hair (1e-12)
// larger than the radius and the binning floor((x - lo) / size), clamped to the grid, is monotone. Up to
// rounding: with more than about 1e4 cells along an axis, the binning's rounding can exceed that hair, and a
// pair within rounding of the radius may land two cells apart and be missed. At r = R every kernel but the
// truncated Gaussian has W = W' = 0, and the Gaussian's gradient there is about e^-9 of its scale, so no
// result moves (a review, 2026-11-28, which compared with brute force, 2D and 3D, and found no difference).
// Clamping keeps stray particles (outside the domain given to build) in the border cells: slower, never
// wrong.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <omp.h>

#include "sphfsi/fluid/grid_limits.hpp"
#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

template <int Dim>
class CellGrid {
public:
    struct Range {
        std::uint32_t begin, end;  // candidate neighbours j in [begin, end) of the sorted order
        Vec<Dim> shift;            // add to x_j: periodic image closest to the cell being searched
    };
    static constexpr int rows = Dim == 2 ? 3 : 9;
    static constexpr int max_ranges = rows * 2;  // per row: the in-grid run plus at most one wrapped cell

    // lo/hi: domain to grid (for a periodic axis, [lo, hi) is exactly one period).
    void configure(const Vec<Dim>& lo, const Vec<Dim>& hi, double radius, const std::array<bool, Dim>& periodic) {
        lo_ = lo;
        periodic_ = periodic;
        // A hair larger than the radius so rounding in the binning can never separate a true pair by two cells.
        const double size = radius * kCellOverSupport;
        double cells = 1.0;  // counted in doubles first: an absurd domain must not overflow the count
        std::array<double, Dim> along{};
        for (int k = 0; k < Dim; ++k) {
            const double len = hi[k] - lo[k];
            if (!(len >= 0.0)) throw std::invalid_argument("cell grid: empty or invalid domain");
            along[static_cast<std::size_t>(k)] = periodic[k] ? periodic_cells(len, radius) : std::max(1.0, std::ceil(len / size));
            if (periodic[k] && along[static_cast<std::size_t>(k)] < 3)
                throw std::invalid_argument("cell grid: periodic length " + std::to_string(len) +
                                            " m holds fewer than 3 cells of one support radius (" + std::to_string(radius) + " m)");
            cells *= along[static_cast<std::size_t>(k)];
        }
        if (cells > kMaxCells)
            throw std::invalid_argument("cell grid: " + std::to_string(cells) + " cells of " + std::to_string(radius) +
                                        " m, more than its 32-bit cell indices number");
        ncells_ = 1;
        for (int k = 0; k < Dim; ++k) {
            const double len = hi[k] - lo[k];
            n_[k] = static_cast<int>(along[static_cast<std::size_t>(k)]);
            cell_size_[k] = periodic[k] ? len / n_[k] : size;
            period_[k] = periodic[k] ? len : 0.0;
            inv_size_[k] = 1.0 / cell_size_[k];
            ncells_ *= static_cast<std::size_t>(n_[k]);
        }
        radius_ = radius;
    }

    // Bins `x` and writes the stable sorting permutation: order[new_index] = old_index. After the caller
    // reorders its arrays with `order`, cell c holds sorted indices [cell_begin(c), cell_end(c)).
    // Points for which excluded(i) is true go after every cell, where no search ever looks.
    template <class Excluded>
    void build(const std::vector<Vec<Dim>>& x, std::vector<std::uint32_t>& order, Excluded&& excluded) {
        const std::size_t n = x.size();
        cell_of_.resize(n);
        const long long nn = static_cast<long long>(n);
        const std::uint32_t outside = static_cast<std::uint32_t>(ncells_);
#pragma omp parallel for schedule(static)
        for (long long i = 0; i < nn; ++i) {
            const auto k = static_cast<std::size_t>(i);
            cell_of_[k] = excluded(k) ? outside : cell_index(x[k]);
        }
        // Counting sort with the counts one slot further up, so that start_[c + 1] is the insertion cursor of
        // cell c and, once every point is placed, the end of c, i.e. the start of c + 1 (no cursor array).
        start_.assign(ncells_ + 3, 0);
        for (std::size_t i = 0; i < n; ++i) ++start_[cell_of_[i] + 2];
        for (std::size_t c = 2; c < start_.size(); ++c) start_[c] += start_[c - 1];
        order.resize(n);
        for (std::size_t i = 0; i < n; ++i) order[start_[cell_of_[i] + 1]++] = static_cast<std::uint32_t>(i);
    }
    void build(const std::vector<Vec<Dim>>& x, std::vector<std::uint32_t>& order) {
        build(x, order, [](std::size_t) { return false; });
    }

    std::uint32_t cell_index(const Vec<Dim>& p) const {
        std::uint32_t c = 0, stride = 1;
        for (int k = 0; k < Dim; ++k) {
            double t = (p[k] - lo_[k]) * inv_size_[k];
            if (!(t >= 0.0)) t = 0.0;  // also catches NaN: a broken particle is reported elsewhere, not here
            const double top = static_cast<double>(n_[k] - 1);
            if (t > top) t = top;
            c += static_cast<std::uint32_t>(t) * stride;
            stride *= static_cast<std::uint32_t>(n_[k]);
        }
        return c;
    }

    // Candidate ranges for particles of cell c. Returns how many were written to `out`.
    int ranges(std::uint32_t c, Range* out) const {
        int k[3] = {0, 0, 0};
        std::uint32_t rest = c;
        for (int d = 0; d < Dim; ++d) {
            k[d] = static_cast<int>(rest % static_cast<std::uint32_t>(n_[d]));
            rest /= static_cast<std::uint32_t>(n_[d]);
        }
        int count = 0;
        // Offsets along axes 1..Dim-1 pick the row; axis 0 is a contiguous run within the row.
        for (int r = 0; r < rows; ++r) {
            int off[3] = {0, r % 3 - 1, r / 3 - 1};
            Vec<Dim> shift{};
            std::uint32_t row_base = 0, stride = static_cast<std::uint32_t>(n_[0]);
            bool valid = true;
            for (int d = 1; d < Dim; ++d) {
                int kk = k[d] + off[d];
                if (kk < 0 || kk >= n_[d]) {
                    if (!periodic_[d]) { valid = false; break; }
                    shift[d] = kk < 0 ? -period_[d] : period_[d];
                    kk = kk < 0 ? kk + n_[d] : kk - n_[d];
                }
                row_base += static_cast<std::uint32_t>(kk) * stride;
                stride *= static_cast<std::uint32_t>(n_[d]);
            }
            if (!valid) continue;
            const int a = std::max(k[0] - 1, 0), b = std::min(k[0] + 1, n_[0] - 1);
            out[count++] = Range{start_[row_base + a], start_[row_base + b + 1], shift};
            if (periodic_[0]) {
                if (k[0] - 1 < 0) {
                    Vec<Dim> s = shift;
                    s[0] = -period_[0];
                    const std::uint32_t cc = row_base + static_cast<std::uint32_t>(n_[0] - 1);
                    out[count++] = Range{start_[cc], start_[cc + 1], s};
                }
                if (k[0] + 1 >= n_[0]) {
                    Vec<Dim> s = shift;
                    s[0] = period_[0];
                    out[count++] = Range{start_[row_base], start_[row_base + 1], s};
                }
            }
        }
        return count;
    }

    // Calls f(cell, begin, end) for every non-empty cell, in parallel. Threads get contiguous runs of
    // cells holding about equal numbers of particles (empty air cells would unbalance a plain split).
    template <class F>
    void for_each_cell_parallel(F&& f) const {
        const std::uint32_t n = start_.empty() ? 0 : start_[ncells_];
#pragma omp parallel
        {
            const int nt = omp_get_num_threads(), t = omp_get_thread_num();
            const std::size_t c0 = first_cell_of_share(n, t, nt), c1 = first_cell_of_share(n, t + 1, nt);
            for (std::size_t c = c0; c < c1; ++c)
                if (start_[c] != start_[c + 1]) f(static_cast<std::uint32_t>(c), start_[c], start_[c + 1]);
        }
    }

    // Same as above without threads (used inside an enclosing parallel region or for small sets).
    template <class F>
    void for_each_cell(F&& f) const {
        for (std::size_t c = 0; c < ncells_; ++c)
            if (start_[c] != start_[c + 1]) f(static_cast<std::uint32_t>(c), start_[c], start_[c + 1]);
    }

    std::size_t cell_count() const { return ncells_; }
    std::uint32_t cell_begin(std::uint32_t c) const { return start_[c]; }
    std::uint32_t cell_end(std::uint32_t c) const { return start_[c + 1]; }
    double radius() const { return radius_; }
    double radius2() const { return radius_ * radius_; }
    const std::array<bool, Dim>& periodic() const { return periodic_; }
    double period(int axis) const { return period_[axis]; }
    const Vec<Dim>& lo() const { return lo_; }
    std::size_t memory_bytes() const {
        return (start_.capacity() + cell_of_.capacity()) * sizeof(std::uint32_t);
    }

private:
    // First cell of thread t's share: the cell holding sorted particle n * t / nt (so shares are balanced).
    std::size_t first_cell_of_share(std::uint32_t n, int t, int nt) const {
        if (t >= nt) return ncells_;
        if (t == 0) return 0;
        const std::uint32_t target = static_cast<std::uint32_t>(static_cast<std::uint64_t>(n) * t / nt);
        // Cells with start <= target; the share starts at the first cell whose start exceeds the previous holder's.
        auto it = std::upper_bound(start_.begin(), start_.begin() + static_cast<std::ptrdiff_t>(ncells_), target);
        return static_cast<std::size_t>(it - start_.begin());
    }

    Vec<Dim> lo_{};
    std::array<double, Dim> cell_size_{}, inv_size_{}, period_{};
    std::array<int, Dim> n_{};
    std::array<bool, Dim> periodic_{};
    std::size_t ncells_ = 0;
    double radius_ = 0.0;
    std::vector<std::uint32_t> start_, cell_of_;
};

}  // namespace sphfsi::fluid
