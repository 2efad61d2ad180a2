// Rule Chain of the box hierarchy: each box's parent is the lower-numbered box with the nearest
// origin. All origins are hashed once into a grid whose buckets list their boxes in ascending
// order, so the boxes below i in a bucket are a prefix of it: box i searches the cells around
// its own in growing rings, reading only those prefixes and skipping cells farther than the
// nearest box found so far, until the ring's inner edge lies farther than that box; past that
// nothing nearer (or as near) is left unseen.
// When the rings would visit more cells than there are lower boxes, it reads those boxes
// directly instead. Boxes are independent of one another, so they are searched in parallel.
#include "internal.h"
#include "spatial_hash.h"

#include <cmath>
#include <limits>

namespace boxmarch {

namespace {

glm::dvec3 vec3_at(const double* a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

// The nearest box so far by (distance, index). A box at NaN or infinite distance is never taken.
struct Nearest {
    double distance = std::numeric_limits<double>::infinity();
    int64_t box = -1;
    void consider(const double* origins, size_t i, size_t j) {
        const double d = glm::length(vec3_at(origins, i) - vec3_at(origins, j));
        if (d < distance || (d == distance && box >= 0 && int64_t(j) < box)) distance = d, box = int64_t(j);
    }
};

struct ChainGrid {
    double scale = 1.0;  // grid units per object unit (grid_scale)
    std::vector<double> scaled;
    Grid<double> grid;
    int64_t cells[3] = {1, 1, 1};  // cells per axis spanned by the origins
};

// Reads the boxes below i in the bucket of cell (x, y, z), ascending: past a box at distance 0
// none can come nearer or lower (boxes sharing one origin cost one read each).
void read_cell(const ChainGrid& c, const double* origins, size_t i, int64_t x, int64_t y, int64_t z, Nearest& nearest) {
    const uint64_t b = cell_hash(x, y, z, 0) & c.grid.mask;
    for (uint32_t m = c.grid.bucket_start[b], end = c.grid.bucket_start[b + 1]; m < end && c.grid.items[m] < i; ++m) {
        if (nearest.distance == 0.0 && int64_t(c.grid.items[m]) > nearest.box) return;
        nearest.consider(origins, i, c.grid.items[m]);
    }
}

// Distances in cells below are exact to far better than the 1e-3 cell margins (the cell of a
// point is found with at most 2^26 cells per axis, to ~1e-8 of a cell).
int64_t search_rings(const ChainGrid& c, const double* origins, size_t i) {
    int64_t at[3];
    double offset[3];       // where box i lies inside its cell, 0..1 per axis
    int64_t last_ring = 0;  // the ring that covers every cell of the grid
    double edge = 1.0;      // nearest side of its cell, in cells
    for (int d = 0; d < 3; ++d) {
        const double u = (c.scaled[3 * i + d] - c.grid.origin[d]) / c.grid.cell, f = std::floor(u);
        at[d] = int64_t(f);
        offset[d] = u - f;
        last_ring = std::max({last_ring, at[d], c.cells[d] - 1 - at[d]});
        edge = std::min({edge, offset[d], 1.0 - offset[d]});
    }
    // Gap between box i and the cell `step` cells away along axis d, in cells.
    auto gap = [&](int d, int64_t step) {
        return step > 0 ? double(step) - offset[d] : step < 0 ? double(-step) - 1.0 + offset[d] : 0.0;
    };
    Nearest nearest;
    double visited = 0.0;
    for (int64_t r = 0;; ++r) {
        visited += r == 0 ? 1.0 : 24.0 * double(r) * double(r) + 2.0;
        if (visited > double(i) + 27.0) {
            for (size_t j = 0; j < i; ++j) nearest.consider(origins, i, j);
            return nearest.box;
        }
        const double reach = nearest.distance * c.scale / c.grid.cell + 1e-3;  // cells farther hold nothing nearer
        for (int64_t dx = -r; dx <= r; ++dx)
            for (int64_t dy = -r; dy <= r; ++dy) {
                const bool side = dx == -r || dx == r || dy == -r || dy == r;
                const double gap2 = gap(0, dx) * gap(0, dx) + gap(1, dy) * gap(1, dy);
                for (int64_t dz = -r; dz <= r; dz += side ? 1 : std::max<int64_t>(1, 2 * r))
                    if (gap2 + gap(2, dz) * gap(2, dz) <= reach * reach)
                        read_cell(c, origins, i, at[0] + dx, at[1] + dy, at[2] + dz, nearest);
            }
        // Boxes outside rings 0..r are at least r cells and the nearest side of i's own cell away.
        if (r >= last_ring || nearest.distance * c.scale < (double(r) + edge - 1e-3) * c.grid.cell) return nearest.box;
    }
}

}  // namespace

// Boxes with a NaN or infinite origin coordinate are at NaN or infinite distance from every box:
// they are nobody's parent and have none.
void chain_parents(int32_t* parent, const double* origins, size_t count) {
    ChainGrid c;
    std::vector<uint32_t> finite;
    double largest = 0.0;
    for (size_t i = 0; i < count; ++i) {
        const glm::dvec3 o = vec3_at(origins, i);
        if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.z)) continue;
        finite.push_back(uint32_t(i));
        largest = std::max({largest, std::abs(o.x), std::abs(o.y), std::abs(o.z)});
    }
    c.scale = grid_scale(largest);
    c.scaled.resize(count * 3);
    for (size_t i = 0; i < count * 3; ++i) c.scaled[i] = origins[i] * c.scale;
    build_grid(c.grid, c.scaled.data(), finite, 0.0, nullptr);
    for (int d = 0; d < 3; ++d) {
        double top = c.grid.origin[d];
        for (uint32_t i : finite) top = std::max(top, c.scaled[3 * size_t(i) + d]);
        c.cells[d] = int64_t(std::floor((top - c.grid.origin[d]) / c.grid.cell)) + 1;
    }
    std::fill(parent, parent + count, -1);
    // In bucket order, so that boxes searched one after the other read the same cells.
    const size_t n = c.grid.items.size(), parts = thread_count(0, n);
    run_parallel(parts, [&](size_t part) {
        for (size_t k = n * part / parts; k < n * (part + 1) / parts; ++k) {
            const uint32_t i = c.grid.items[k];
            parent[i] = int32_t(search_rings(c, origins, i));
        }
    });
}

}  // namespace boxmarch
