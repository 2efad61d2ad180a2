// For each point, the candidate nearest to it. The finite candidates are put once into a k-d
// tree (kd_tree.h, as the CHAIN hierarchy rule does); each point descends it nearer side first,
// skipping nodes whose bounds lie farther than the nearest candidate found so far. The tree
// follows the candidates wherever they are, so points far from a compact set of candidates cost
// a descent, not a pass over every candidate. Points are independent of one another, so they are
// searched in parallel.
#include "internal.h"
#include "kd_tree.h"
#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace boxmarch {

namespace {

// The squared length the contract names, summed in its order; grows with each |component|.
double squared_norm(const double v[3]) { return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]; }

}  // namespace

void nearest_points_counted(int64_t* nearest, const double* points, size_t point_count, const double* candidates,
                            size_t candidate_count, int threads, SearchWork* work) {
    // Squares in grid units, scaled by a power of 2 so that none overflows (grid_scale).
    double largest = 0.0;
    std::vector<uint32_t> finite;
    for (const auto& [set, count] : {std::pair{points, point_count}, std::pair{candidates, candidate_count}})
        for (size_t i = 0; i < count; ++i)
            if (finite_point(set + 3 * i)) {
                largest = std::max({largest, std::abs(set[3 * i]), std::abs(set[3 * i + 1]), std::abs(set[3 * i + 2])});
                if (set == candidates) finite.push_back(uint32_t(i));
            }
    const double scale = grid_scale(largest);
    std::vector<double> scaled(candidates, candidates + 3 * candidate_count);
    for (double& v : scaled) v *= scale;
    KdTree tree;
    build_kd_tree(tree, scaled.data(), std::move(finite));
    std::fill(nearest, nearest + point_count, -1);
    const size_t parts = thread_count(threads, point_count);
    std::mutex counted;
    run_parallel(parts, [&](size_t part) {
        SearchWork done;
        for (size_t i = point_count * part / parts; i < point_count * (part + 1) / parts; ++i) {
            if (!finite_point(points + 3 * i)) continue;
            const double p[3] = {points[3 * i] * scale, points[3 * i + 1] * scale, points[3 * i + 2] * scale};
            double best = INFINITY;
            auto distance = [&](uint32_t j) {
                const double* q = scaled.data() + 3 * size_t(j);
                const double v[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
                return squared_norm(v);
            };
            auto bound = [&](const KdTree::Node& n) {
                double gap[3];
                gap_to(p, n, gap);
                return squared_norm(gap);
            };
            nearest_in_tree(tree, UINT32_MAX, distance, bound, best, nearest[i], done);
        }
        const std::lock_guard<std::mutex> lock(counted);
        if (work) work->add(done);
    });
}

void nearest_points(int64_t* nearest, const double* points, size_t point_count, const double* candidates,
                    size_t candidate_count, int threads) {
    nearest_points_counted(nearest, points, point_count, candidates, candidate_count, threads, nullptr);
}

}  // namespace boxmarch
