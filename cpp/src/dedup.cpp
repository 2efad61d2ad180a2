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
            std::sort(sorted_b.begin(), sorted_b.end(),
                      [&](uint32_t u, uint32_t v) { return positions[3 * size_t(u)] < positions[3 * size_t(v)]; });
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
                    if (dist2(a[i], sorted_b[k]) <= r2)
                        cand.push_back(uint32_t(std::lower_bound(b, b + n, sorted_b[k]) - b));
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

size_t find_duplicate_submeshes(int32_t* duplicate_of, const float* positions, const int32_t* submesh_of_vertex,
                                size_t vertex_count, size_t submesh_count, const uint8_t* candidate, double tolerance,
                                int /*threads*/) {
    check_submesh_ids(submesh_of_vertex, vertex_count, submesh_count);
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
    // Submeshes in id order, each compared with the kept ones near it (earliest first): the grid
    // starts empty and takes each submesh found not to be a duplicate, so a pile of copies costs
    // a comparison with the kept original each, and no list of pairs is ever made.
    std::vector<uint32_t> listed;
    for (size_t s = 0; s < submesh_count; ++s)
        if (own_group[s] >= 0) listed.push_back(uint32_t(s));
    Grid<double> g;
    build_grid(g, centroids.data(), listed, reach, nullptr);
    g.bucket_end.assign(g.bucket_start.begin(), g.bucket_start.end() - 1);  // nothing kept yet
    std::vector<uint32_t> slot_of(submesh_count, UINT32_MAX), bucket_of_slot(g.items.size());
    for (uint32_t m = 0; m < g.items.size(); ++m) slot_of[g.items[m]] = m;
    for (size_t bk = 0; bk + 1 < g.bucket_start.size(); ++bk)
        std::fill(bucket_of_slot.begin() + g.bucket_start[bk], bucket_of_slot.begin() + g.bucket_start[bk + 1],
                  uint32_t(bk));
    const double reach2 = reach * reach;

    Matcher matcher{positions, tolerance * tolerance, {}, {}, {}, {}, {}, {}, {}, {}, {}};
    size_t duplicates = 0;
    std::vector<uint32_t> near;
    for (uint32_t later : listed) {
        const double* c = &centroids[3 * size_t(later)];
        const uint32_t n = offsets[later + 1] - offsets[later];
        near.clear();
        visit_near(g, c, reach, 0, [&](uint32_t m) {
            const uint32_t earlier = g.items[m];
            if (offsets[earlier + 1] - offsets[earlier] == n && distance2(g, c, m) <= reach2) near.push_back(earlier);
            return false;
        });
        std::sort(near.begin(), near.end());
        for (uint32_t earlier : near)
            if (matcher.matches(&items[offsets[later]], &items[offsets[earlier]], n)) {
                duplicate_of[later] = int32_t(earlier);
                ++duplicates;
                break;
            }
        if (duplicate_of[later] >= 0) continue;
        // Kept: move it into its bucket's kept prefix.
        const uint32_t m = slot_of[later], bk = bucket_of_slot[m], to = g.bucket_end[bk]++;
        const uint32_t other = g.items[to];
        std::swap(g.items[m], g.items[to]);
        for (int d = 0; d < 3; ++d)
            std::swap(g.sorted_positions[3 * size_t(m) + d], g.sorted_positions[3 * size_t(to) + d]);
        slot_of[other] = m;
        slot_of[later] = to;
    }
    return duplicates;
}

}  // namespace boxmarch
