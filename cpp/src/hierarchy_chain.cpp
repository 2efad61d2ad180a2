// Rule Chain of the box hierarchy: each box's parent is the lower-numbered box with the nearest
// origin. All origins are hashed once into a grid whose buckets list their boxes in ascending
// order, so the boxes below i in a bucket are a prefix of it: box i searches the cells around
// its own in growing rings, reading only those prefixes and skipping cells farther than the
// nearest box found so far, until the ring's inner edge lies farther than that box; past that
// nothing nearer (or as near) is left unseen.
// When the rings would visit more cells than there are lower boxes, it reads those boxes
// directly instead. Boxes are independent of one another, so they are searched in parallel.
#include "internal.h"
#include "ring_search.h"

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

// Reads the boxes below i in bucket b, ascending: past a box at distance 0 none can come nearer
// or lower (boxes sharing one origin cost one read each).
void read_bucket(const RingGrid& c, const double* origins, size_t i, uint64_t b, Nearest& nearest) {
    for (uint32_t m = c.grid.bucket_start[b], end = c.grid.bucket_start[b + 1]; m < end && c.grid.items[m] < i; ++m) {
        if (nearest.distance == 0.0 && int64_t(c.grid.items[m]) > nearest.box) return;
        nearest.consider(origins, i, c.grid.items[m]);
    }
}

int64_t nearest_lower(const RingGrid& c, const double* origins, size_t i) {
    Nearest nearest;
    search_rings(
            c, &c.scaled[3 * i], double(i), [&](uint64_t b) { read_bucket(c, origins, i, b, nearest); },
            [&] { return nearest.distance * c.scale; },
            [&] {
                for (size_t j = 0; j < i; ++j) nearest.consider(origins, i, j);
            });
    return nearest.box;
}

}  // namespace

// Boxes with a NaN or infinite origin coordinate are at NaN or infinite distance from every box:
// they are nobody's parent and have none.
void chain_parents(int32_t* parent, const double* origins, size_t count) {
    RingGrid c;
    build_ring_grid(c, origins, count, 0.0);
    std::fill(parent, parent + count, -1);
    // In bucket order, so that boxes searched one after the other read the same cells.
    const size_t n = c.grid.items.size(), parts = thread_count(0, n);
    run_parallel(parts, [&](size_t part) {
        for (size_t k = n * part / parts; k < n * (part + 1) / parts; ++k) {
            const uint32_t i = c.grid.items[k];
            parent[i] = int32_t(nearest_lower(c, origins, i));
        }
    });
}

}  // namespace boxmarch
