// Nearest-point search on a hash grid in growing rings of cells, shared by the CHAIN hierarchy
// rule (hierarchy_chain.cpp) and nearest_points (nearest_points.cpp); not public.
#pragma once

#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace boxmarch {

// The finite points of a set hashed into a grid whose buckets list their points in ascending
// order (build_grid keeps that order).
struct RingGrid {
    double scale = 1.0;  // grid units per object unit (grid_scale)
    std::vector<double> scaled;
    Grid<double> grid;
    int64_t cells[3] = {1, 1, 1};  // cells per axis spanned by the points
    std::vector<uint32_t> finite;  // the points hashed, ascending
};

inline bool finite_point(const double* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Builds r over points[count * 3], leaving out points with a NaN or infinite coordinate. The
// scale brings magnitudes up to max(largest, the points' largest) to at most 2^300.
inline void build_ring_grid(RingGrid& r, const double* points, size_t count, double largest) {
    for (size_t i = 0; i < count; ++i) {
        if (!finite_point(points + 3 * i)) continue;
        r.finite.push_back(uint32_t(i));
        largest =
                std::max({largest, std::abs(points[3 * i]), std::abs(points[3 * i + 1]), std::abs(points[3 * i + 2])});
    }
    r.scale = grid_scale(largest);
    r.scaled.resize(count * 3);
    for (size_t i = 0; i < count * 3; ++i) r.scaled[i] = points[i] * r.scale;
    build_grid(r.grid, r.scaled.data(), r.finite, 0.0, nullptr);
    for (int d = 0; d < 3; ++d) {
        double top = r.grid.origin[d];
        for (uint32_t i : r.finite) top = std::max(top, r.scaled[3 * size_t(i) + d]);
        r.cells[d] = int64_t(std::floor((top - r.grid.origin[d]) / r.grid.cell)) + 1;
    }
}

// Searches the cells around p (finite, in grid units: scaled like r) in growing rings, calling
// read(bucket) for each cell that may hold a point nearer than distance() (the nearest found so
// far, in grid units; infinity while none), skipping cells farther, until the ring's inner edge
// lies farther than that point: past that nothing nearer (or as near) is left unseen. When the
// rings would visit more cells than `direct` + 27, or p lies too far from the grid to number its
// cell, calls read_all() once instead and stops. read may see points of other cells hashed to
// the same bucket: callers decide by the true distance.
// Distances in cells below are exact to far better than the 1e-3 cell margins (the cell of a
// point is found with at most 2^26 cells per axis, to ~1e-8 of a cell).
template <class Read, class Distance, class ReadAll>
void search_rings(const RingGrid& r, const double p[3], double direct, Read&& read, Distance&& distance,
                  ReadAll&& read_all) {
    const Grid<double>& g = r.grid;
    int64_t at[3];
    double offset[3];       // where p lies inside its cell, 0..1 per axis
    int64_t last_ring = 0;  // the ring that covers every cell of the grid
    double edge = 1.0;      // nearest side of its cell, in cells
    for (int d = 0; d < 3; ++d) {
        const double u = (p[d] - g.origin[d]) / g.cell, f = std::floor(u);
        if (!(std::abs(f) < 0x1p40)) return read_all();
        at[d] = int64_t(f);
        offset[d] = u - f;
        last_ring = std::max({last_ring, at[d], r.cells[d] - 1 - at[d]});
        edge = std::min({edge, offset[d], 1.0 - offset[d]});
    }
    // Gap between p and the cell `step` cells away along axis d, in cells.
    auto gap = [&](int d, int64_t step) {
        return step > 0 ? double(step) - offset[d] : step < 0 ? double(-step) - 1.0 + offset[d] : 0.0;
    };
    double visited = 0.0;
    for (int64_t ring = 0;; ++ring) {
        visited += ring == 0 ? 1.0 : 24.0 * double(ring) * double(ring) + 2.0;
        if (visited > direct + 27.0) return read_all();
        const double reach = distance() / g.cell + 1e-3;  // cells farther hold nothing nearer
        for (int64_t dx = -ring; dx <= ring; ++dx)
            for (int64_t dy = -ring; dy <= ring; ++dy) {
                const bool side = dx == -ring || dx == ring || dy == -ring || dy == ring;
                const double gap2 = gap(0, dx) * gap(0, dx) + gap(1, dy) * gap(1, dy);
                for (int64_t dz = -ring; dz <= ring; dz += side ? 1 : std::max<int64_t>(1, 2 * ring))
                    if (gap2 + gap(2, dz) * gap(2, dz) <= reach * reach)
                        read(cell_hash(at[0] + dx, at[1] + dy, at[2] + dz, 0) & g.mask);
            }
        // Points outside rings 0..ring are at least ring cells and the nearest side of p's own cell away.
        if (ring >= last_ring || distance() < (double(ring) + edge - 1e-3) * g.cell) return;
    }
}

}  // namespace boxmarch
