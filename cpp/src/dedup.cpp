// Duplicate submeshes: same vertex count and a one-to-one pairing of vertices within tolerance.
// Candidates come from a hash of centroids: the centroids of two such submeshes are within
// tolerance too (the mean of the paired differences is no longer than the longest of them), so
// only nearby submeshes are ever compared.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace boxmarch {

namespace {

// Small submeshes compare every vertex pair; larger ones sort the other side along x first.
constexpr uint32_t kBruteForceLimit = 48;

struct Matcher {
    const float* positions;
    double r2;
    std::vector<uint32_t> cand_start, cand, sorted_b;
    std::vector<double> sorted_x;
    std::vector<int32_t> match_a, match_b, parent_b;
    std::vector<uint32_t> seen_b, queue;
    uint32_t stamp = 0;

    double dist2(uint32_t u, uint32_t v) const {
        const float* p = positions + 3 * size_t(u);
        const float* q = positions + 3 * size_t(v);
        const double dx = double(p[0]) - q[0], dy = double(p[1]) - q[1], dz = double(p[2]) - q[2];
        return dx * dx + dy * dy + dz * dz;
    }

    // True when the n vertices a[] pair one-to-one with the n vertices b[] within the radius.
    bool matches(const uint32_t* a, const uint32_t* b, uint32_t n) {
        cand_start.assign(n + 1, 0);
        cand.clear();
        if (n > kBruteForceLimit) {
            sorted_b.assign(b, b + n);
            std::sort(sorted_b.begin(), sorted_b.end(), [&](uint32_t u, uint32_t v) {
                return positions[3 * size_t(u)] < positions[3 * size_t(v)];
            });
            sorted_x.resize(n);
            for (uint32_t k = 0; k < n; ++k) sorted_x[k] = positions[3 * size_t(sorted_b[k])];
        }
        const double r = std::sqrt(r2);
        for (uint32_t i = 0; i < n; ++i) {
            if (n <= kBruteForceLimit) {
                for (uint32_t j = 0; j < n; ++j)
                    if (dist2(a[i], b[j]) <= r2) cand.push_back(j);
            } else {
                const double x = positions[3 * size_t(a[i])];
                auto first = std::lower_bound(sorted_x.begin(), sorted_x.end(), x - r * (1 + 1e-12));
                for (auto it = first; it != sorted_x.end() && *it <= x + r * (1 + 1e-12); ++it) {
                    const uint32_t k = uint32_t(it - sorted_x.begin());
                    if (dist2(a[i], sorted_b[k]) <= r2) cand.push_back(uint32_t(std::lower_bound(b, b + n, sorted_b[k]) - b));
                }
            }
            if (cand.size() == cand_start[i]) return false;  // a vertex with no partner
            cand_start[i + 1] = uint32_t(cand.size());
        }
        // Maximum matching: greedy first, then a breadth-first augmenting path per free vertex.
        match_a.assign(n, -1);
        match_b.assign(n, -1);
        parent_b.assign(n, -1);
        seen_b.assign(n, 0);
        stamp = 0;
        for (uint32_t i = 0; i < n; ++i)
            for (uint32_t k = cand_start[i]; k < cand_start[i + 1]; ++k)
                if (match_b[cand[k]] < 0) {
                    match_b[cand[k]] = int32_t(i);
                    match_a[i] = int32_t(cand[k]);
                    break;
                }
        for (uint32_t i = 0; i < n; ++i) {
            if (match_a[i] >= 0) continue;
            ++stamp;
            queue.assign(1, i);
            int32_t free_b = -1;
            for (size_t head = 0; head < queue.size() && free_b < 0; ++head) {
                const uint32_t x = queue[head];
                for (uint32_t k = cand_start[x]; k < cand_start[x + 1]; ++k) {
                    const uint32_t j = cand[k];
                    if (seen_b[j] == stamp) continue;
                    seen_b[j] = stamp;
                    parent_b[j] = int32_t(x);
                    if (match_b[j] < 0) {
                        free_b = int32_t(j);
                        break;
                    }
                    queue.push_back(uint32_t(match_b[j]));
                }
            }
            if (free_b < 0) return false;
            for (int32_t j = free_b;;) {  // flip the path back to i
                const int32_t x = parent_b[size_t(j)];
                const int32_t previous = match_a[size_t(x)];
                match_a[size_t(x)] = j;
                match_b[size_t(j)] = x;
                if (uint32_t(x) == i) break;
                j = previous;
            }
        }
        return true;
    }
};

}  // namespace

size_t find_duplicate_submeshes(int32_t* duplicate_of, const float* positions,
                                const int32_t* submesh_of_vertex, size_t vertex_count,
                                size_t submesh_count, const uint8_t* candidate, double tolerance,
                                int threads) {
    check_radius(tolerance, "tolerance");
    check_finite_positions(positions, vertex_count);
    std::vector<uint32_t> offsets(submesh_count + 1), items(vertex_count);
    group_by_submesh(offsets.data(), items.data(), submesh_of_vertex, vertex_count, submesh_count);

    std::vector<double> centroids(3 * submesh_count, 0.0);
    std::vector<int32_t> own_group(submesh_count, -1);  // -1 leaves non-candidates out of the hash
    double largest = 0.0;
    for (size_t s = 0; s < submesh_count; ++s) {
        duplicate_of[s] = -1;
        if (candidate && !candidate[s]) continue;
        own_group[s] = int32_t(s);
        double sum[3] = {0, 0, 0};
        for (uint32_t k = offsets[s]; k < offsets[s + 1]; ++k)
            for (int d = 0; d < 3; ++d) sum[d] += positions[3 * size_t(items[k]) + d];
        const double count = double(offsets[s + 1] - offsets[s]);
        for (int d = 0; d < 3; ++d) {
            centroids[3 * s + d] = sum[d] / count;
            largest = std::max(largest, std::abs(centroids[3 * s + d]));
        }
    }
    // Centroid rounding is far below 1e-9 of the coordinates' size: widen by that much.
    const double reach = tolerance * (1 + 1e-9) + largest * 1e-9;
    std::vector<PointPair> pairs = close_pairs(centroids.data(), submesh_count, reach, own_group.data(), threads);
    for (PointPair& p : pairs) std::swap(p.first, p.second);  // (later, earlier)
    std::sort(pairs.begin(), pairs.end());

    Matcher matcher{positions, tolerance * tolerance, {}, {}, {}, {}, {}, {}, {}, {}, {}};
    size_t duplicates = 0;
    for (const PointPair& p : pairs) {
        const uint32_t later = p.first, earlier = p.second;
        if (duplicate_of[later] >= 0 || duplicate_of[earlier] >= 0) continue;  // decided, or not kept
        const uint32_t n = offsets[later + 1] - offsets[later];
        if (offsets[earlier + 1] - offsets[earlier] != n) continue;
        if (matcher.matches(&items[offsets[later]], &items[offsets[earlier]], n)) {
            duplicate_of[later] = int32_t(earlier);
            ++duplicates;
        }
    }
    return duplicates;
}

}  // namespace boxmarch
