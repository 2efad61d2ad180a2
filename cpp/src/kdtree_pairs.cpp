// Fixed-radius neighbour pairs by nanoflann radius searches (nanoflann: k-d trees after FLANN, Muja and
// Lowe): the reference for the hash grid.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <nanoflann.hpp>

#include <cmath>

namespace boxmarch {

namespace {

struct PointCloud {
    const float* positions;
    size_t count;
    size_t kdtree_get_point_count() const { return count; }
    double kdtree_get_pt(size_t i, size_t d) const { return double(positions[3 * i + d]); }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
        return false;
    }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointCloud, double>, PointCloud,
                                                 3, uint32_t>;

}  // namespace

size_t find_close_pairs_kdtree(uint32_t* pairs, size_t capacity, const float* positions, size_t count, double radius,
                               const int32_t* group_of_point) {
    check_radius(radius, "radius");
    check_finite_positions(positions, count);
    PointCloud cloud{positions, count};
    Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree.buildIndex();
    const double r2 = radius * radius;
    // nanoflann keeps distances strictly below its radius: search a hair wider, then apply the
    // inclusive test on the exact squared distance.
    const double search = r2 * (1.0 + 1e-9) + 1e-300;
    std::vector<std::pair<uint32_t, double>> hits;
    std::vector<PointPair> found;
    nanoflann::SearchParams params;
    params.sorted = false;
    for (size_t i = 0; i < count; ++i) {
        if (group_of_point && group_of_point[i] < 0) continue;
        const double q[3] = {double(positions[3 * i]), double(positions[3 * i + 1]), double(positions[3 * i + 2])};
        tree.radiusSearch(q, search, hits, params);
        for (const auto& hit : hits) {
            const uint32_t j = hit.first;
            if (j <= i) continue;
            if (group_of_point && (group_of_point[j] < 0 || group_of_point[j] == group_of_point[i])) continue;
            const double dx = q[0] - positions[3 * size_t(j)], dy = q[1] - positions[3 * size_t(j) + 1],
                         dz = q[2] - positions[3 * size_t(j) + 2];
            if (dx * dx + dy * dy + dz * dz <= r2) found.emplace_back(uint32_t(i), j);
        }
    }
    return write_sorted_pairs(pairs, capacity, found);
}

}  // namespace boxmarch
