// Plans for merging by distance inside each submesh with a merge that works on a whole vertex
// selection (Blender's own): select only vertices that have a partner in their own submesh, and
// put submeshes whose selected vertices come within the distance of each other into different
// passes, so one pass never merges across submeshes.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <cmath>
#include <algorithm>
#include <vector>

namespace boxmarch {

size_t merge_passes(int32_t* pass_of_vertex, const float* positions,
                    const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count,
                    const uint8_t* chosen, double distance, int threads) {
    check_radius(distance, "distance");
    check_finite_positions(positions, vertex_count);
    // Every vertex its own group: all close pairs among vertices of chosen submeshes.
    std::vector<int32_t> own(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) own[v] = chosen[size_t(submesh_of_vertex[v])] ? int32_t(v) : -1;
    const std::vector<PointPair> pairs = close_pairs(positions, vertex_count, distance * (1 + 1e-6), own.data(), threads);

    std::vector<uint8_t> candidate(vertex_count, 0), has_candidate(submesh_count, 0);
    for (const PointPair& p : pairs)
        if (submesh_of_vertex[p.first] == submesh_of_vertex[p.second]) {
            candidate[p.first] = candidate[p.second] = 1;
            has_candidate[size_t(submesh_of_vertex[p.first])] = 1;
        }
    // Conflicts between submeshes as (later, earlier), without repeats.
    std::vector<PointPair> conflicts;
    for (const PointPair& p : pairs) {
        const uint32_t a = uint32_t(submesh_of_vertex[p.first]), b = uint32_t(submesh_of_vertex[p.second]);
        if (a != b && candidate[p.first] && candidate[p.second]) conflicts.emplace_back(std::max(a, b), std::min(a, b));
    }
    std::sort(conflicts.begin(), conflicts.end());
    conflicts.erase(std::unique(conflicts.begin(), conflicts.end()), conflicts.end());

    // Greedy colouring in id order: each submesh takes the lowest pass no earlier neighbour has.
    std::vector<int32_t> pass_of_submesh(submesh_count, -1);
    size_t passes = 0, k = 0;
    std::vector<uint8_t> taken;
    for (size_t s = 0; s < submesh_count; ++s) {
        if (!has_candidate[s]) continue;
        taken.assign(passes + 1, 0);
        for (; k < conflicts.size() && conflicts[k].first == s; ++k)
            taken[size_t(pass_of_submesh[conflicts[k].second])] = 1;
        const size_t pass = size_t(std::find(taken.begin(), taken.end(), 0) - taken.begin());
        pass_of_submesh[s] = int32_t(pass);
        passes = std::max(passes, pass + 1);
    }
    for (size_t v = 0; v < vertex_count; ++v)
        pass_of_vertex[v] = candidate[v] ? pass_of_submesh[size_t(submesh_of_vertex[v])] : -1;
    return passes;
}

}  // namespace boxmarch

namespace boxmarch {

size_t merge_targets(int32_t* target, float* merged_positions, const float* positions,
                     const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count,
                     const uint8_t* chosen, double distance, int threads) {
    check_radius(distance, "distance");
    check_finite_positions(positions, vertex_count);
    (void)submesh_count;
    std::vector<int32_t> own(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) own[v] = chosen[size_t(submesh_of_vertex[v])] ? int32_t(v) : -1;
    std::vector<PointPair> pairs = close_pairs(positions, vertex_count, distance, own.data(), threads);
    // Same-submesh neighbours of each vertex, ascending (CSR).
    std::vector<uint32_t> start(vertex_count + 1, 0);
    size_t kept = 0;
    for (const PointPair& p : pairs)
        if (submesh_of_vertex[p.first] == submesh_of_vertex[p.second]) pairs[kept++] = p;
    pairs.resize(kept);
    for (const PointPair& p : pairs) {
        ++start[p.first + 1];
        ++start[p.second + 1];
    }
    for (size_t v = 0; v < vertex_count; ++v) start[v + 1] += start[v];
    std::vector<uint32_t> cursor(start.begin(), start.end() - 1), next(2 * pairs.size());
    for (const PointPair& p : pairs) {
        next[cursor[p.first]++] = p.second;
        next[cursor[p.second]++] = p.first;
    }
    for (size_t v = 0; v < vertex_count; ++v) {
        target[v] = -1;
        std::sort(next.begin() + start[v], next.begin() + start[v + 1]);
    }
    std::copy(positions, positions + 3 * vertex_count, merged_positions);
    size_t merged = 0;
    std::vector<uint32_t> members;
    for (size_t v = 0; v < vertex_count; ++v) {
        if (target[v] >= 0) continue;
        target[v] = int32_t(v);
        members.assign(1, uint32_t(v));
        for (uint32_t k = start[v]; k < start[v + 1]; ++k)
            if (target[next[k]] < 0) members.push_back(next[k]);
        if (members.size() == 1) continue;
        double centroid[3] = {0, 0, 0};
        for (uint32_t m : members)
            for (int d = 0; d < 3; ++d) centroid[d] += positions[3 * size_t(m) + d];
        for (double& c : centroid) c /= double(members.size());
        uint32_t chosen_target = members[0];
        if (members.size() > 2) {
            double best = INFINITY;
            for (uint32_t m : members) {
                double d2 = 0;
                for (int d = 0; d < 3; ++d) d2 += (positions[3 * size_t(m) + d] - centroid[d]) * (positions[3 * size_t(m) + d] - centroid[d]);
                if (d2 < best || (d2 == best && m < chosen_target)) {
                    best = d2;
                    chosen_target = m;
                }
            }
        }
        for (uint32_t m : members) target[m] = int32_t(chosen_target);
        for (int d = 0; d < 3; ++d) merged_positions[3 * size_t(chosen_target) + d] = float(centroid[d]);
        merged += members.size() - 1;
    }
    return merged;
}

}  // namespace boxmarch
