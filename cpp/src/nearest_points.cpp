// For each point, the candidate nearest to it. The finite candidates are hashed once into a grid
// whose buckets list them in ascending order; each point searches the cells around its own in
// growing rings (ring_search.h, as the CHAIN hierarchy rule does), skipping cells farther than
// the nearest candidate found so far. Points are independent of one another, so they are
// searched in parallel.
#include "internal.h"
#include "ring_search.h"

#include <cmath>
#include <limits>

namespace boxmarch {

namespace {

// The nearest candidate so far by (squared distance, row), in grid units: scaled by a power of
// 2, so that no square overflows and the order is that of the unscaled squares wherever those
// are finite. A candidate at NaN distance is never taken.
struct NearestCandidate {
    double distance2 = std::numeric_limits<double>::infinity();
    int64_t row = -1;
    void consider(const double p[3], const double* scaled, size_t j) {
        const double* q = scaled + 3 * j;
        const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < distance2 || (d2 == distance2 && int64_t(j) < row)) distance2 = d2, row = int64_t(j);
    }
};

int64_t nearest_candidate(const RingGrid& c, const double p[3]) {
    NearestCandidate nearest;
    // Past a candidate at distance 0 none can come nearer or lower (buckets are ascending).
    auto read_bucket = [&](uint64_t b) {
        for (uint32_t m = c.grid.bucket_start[b], end = c.grid.bucket_start[b + 1]; m < end; ++m) {
            if (nearest.distance2 == 0.0 && int64_t(c.grid.items[m]) > nearest.row) return;
            nearest.consider(p, c.scaled.data(), c.grid.items[m]);
        }
    };
    search_rings(
            c, p, double(c.finite.size()), read_bucket, [&] { return std::sqrt(nearest.distance2); },
            [&] {
                for (uint32_t j : c.finite) nearest.consider(p, c.scaled.data(), j);
            });
    return nearest.row;
}

}  // namespace

void nearest_points(int64_t* nearest, const double* points, size_t point_count, const double* candidates,
                    size_t candidate_count, int threads) {
    double largest = 0.0;
    for (size_t i = 0; i < point_count; ++i)
        if (finite_point(points + 3 * i))
            largest = std::max(
                    {largest, std::abs(points[3 * i]), std::abs(points[3 * i + 1]), std::abs(points[3 * i + 2])});
    RingGrid c;
    build_ring_grid(c, candidates, candidate_count, largest);
    std::fill(nearest, nearest + point_count, -1);
    if (c.finite.empty()) return;
    const size_t parts = thread_count(threads, point_count);
    run_parallel(parts, [&](size_t part) {
        for (size_t i = point_count * part / parts; i < point_count * (part + 1) / parts; ++i) {
            if (!finite_point(points + 3 * i)) continue;
            const double p[3] = {points[3 * i] * c.scale, points[3 * i + 1] * c.scale, points[3 * i + 2] * c.scale};
            nearest[i] = nearest_candidate(c, p);
        }
    });
}

}  // namespace boxmarch
