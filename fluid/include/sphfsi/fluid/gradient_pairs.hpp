#pragma once
// A particle's interacting pairs at fixed positions, with each pair's kernel-gradient factor W'(r)/r, held for
// a loop that sums over the same pairs many times. PCISPH's pressure-force pass is that loop: every correction
// of a step evaluates it at the positions of time t with new pressures, and without this list each pass scans
// all candidates of the 3^Dim cells around a particle (about three times as many as lie within the support)
// and evaluates a square root and the kernel for each pair again.
//
// Layout (compressed rows): particle i's pairs are [first[i], first[i + 1]) of `j` and `grad_factor`, in the
// order the cell search meets them, so a sum over the list adds the same terms in the same order as the scan
// it replaces. `shift` is the periodic image to add to x_j, held only when the grid has a periodic axis
// (otherwise empty). The list is built in two exact passes (count, then fill) so that no buffer is held
// twice: its memory is 12 bytes a pair (plus 16 on a periodic grid) and 8 a particle.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sphfsi/fluid/cell_grid.hpp"
#include "sphfsi/fluid/vec.hpp"

namespace sphfsi::fluid {

template <int Dim>
struct GradientPairs {
    std::vector<std::size_t> first;
    std::vector<std::uint32_t> j;
    std::vector<double> grad_factor;
    std::vector<Vec<Dim>> shift;

    std::size_t memory_bytes() const {
        return first.capacity() * sizeof(std::size_t) + j.capacity() * sizeof(std::uint32_t) +
               grad_factor.capacity() * sizeof(double) + shift.capacity() * sizeof(Vec<Dim>);
    }

    // Lists the pairs (i, j), j != i at distance 0 < r < the grid's radius of positions x, for every i in a cell
    // with `wanted_i(i)` and every j with `wanted_pair(i, j)`, and their kg.grad_factor(r). n: the particle count
    // (particles in no cell get no pairs).
    template <class KernelG, class WantedI, class WantedPair>
    void build(const CellGrid<Dim>& grid, const std::vector<Vec<Dim>>& x, std::size_t n, const KernelG& kg,
               WantedI&& wanted_i, WantedPair&& wanted_pair) {
        bool periodic = false;
        for (int d = 0; d < Dim; ++d) periodic = periodic || grid.periodic()[static_cast<std::size_t>(d)];
        first.assign(n + 1, 0);
        // Pass 1: each particle's count, in first[i + 1]; then each particle's start, in first[i].
        for_each_pair(grid, x, wanted_i, wanted_pair, [&](std::uint32_t i, std::uint32_t, const Vec<Dim>&, double) {
            ++first[i + 1];
        });
        for (std::size_t i = 0; i < n; ++i) first[i + 1] += first[i];
        size_for(j, first[n]);
        size_for(grad_factor, first[n]);
        size_for(shift, periodic ? first[n] : 0);
        // Pass 2: first[i] is particle i's cursor (only the thread holding i's cell moves it), so it ends at the
        // next particle's start; moving every entry up by one restores the starts.
        for_each_pair(grid, x, wanted_i, wanted_pair, [&](std::uint32_t i, std::uint32_t k, const Vec<Dim>& s, double r2) {
            const std::size_t at = first[i]++;
            j[at] = k;
            grad_factor[at] = kg.grad_factor(std::sqrt(r2));
            if (periodic) shift[at] = s;
        });
        for (std::size_t i = n; i > 0; --i) first[i] = first[i - 1];
        first[0] = 0;
    }

private:
    // Sizes v for `count` entries without copying what it held (pass 2 writes every entry): a vector that must
    // grow is freed before it is allocated again, so old and new are never held together, and it gets 1/16 head
    // room, so that the pair count's drift from step to step seldom reallocates. (resize alone would copy, and
    // double the capacity.)
    template <class T>
    static void size_for(std::vector<T>& v, std::size_t count) {
        if (count > v.capacity()) {
            std::vector<T>().swap(v);
            v.reserve(count + count / 16);
        }
        v.resize(count);
    }

    template <class WantedI, class WantedPair, class F>
    static void for_each_pair(const CellGrid<Dim>& grid, const std::vector<Vec<Dim>>& x, WantedI& wanted_i,
                              WantedPair& wanted_pair, F&& f) {
        const double R2 = grid.radius2();
        grid.for_each_cell_parallel([&](std::uint32_t cell, std::uint32_t begin, std::uint32_t end) {
            typename CellGrid<Dim>::Range ranges[CellGrid<Dim>::max_ranges];
            const int nr = grid.ranges(cell, ranges);
            for (std::uint32_t i = begin; i < end; ++i) {
                if (!wanted_i(i)) continue;
                const Vec<Dim> xi = x[i];
                for (int r = 0; r < nr; ++r)
                    for (std::uint32_t k = ranges[r].begin; k < ranges[r].end; ++k) {
                        if (!wanted_pair(i, k)) continue;
                        const double r2 = norm2(xi - (x[k] + ranges[r].shift));
                        if (r2 < R2 && r2 != 0.0) f(i, k, ranges[r].shift, r2);
                    }
            }
        });
    }
};

}  // namespace sphfsi::fluid
