// Passes for merging by distance inside each submesh with a merge that works on a whole vertex
// selection (Blender's own): submeshes that come within the distance of each other go to
// different passes, so one pass never merges across submeshes.
#include "boxmarch/boxmarch.h"
#include "spatial_hash.h"

#include <algorithm>
#include <vector>

namespace boxmarch {

size_t merge_passes(int32_t* pass_of_submesh, const float* positions,
                    const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count,
                    const uint8_t* chosen, double distance, int threads) {
    check_radius(distance, "distance");
    check_finite_positions(positions, vertex_count);
    std::vector<int32_t> group(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v)
        group[v] = chosen[size_t(submesh_of_vertex[v])] ? submesh_of_vertex[v] : -1;
    std::vector<PointPair> pairs = close_pairs(positions, vertex_count, distance * (1 + 1e-6), group.data(), threads);

    // Conflicts between submeshes as (later, earlier), without repeats.
    for (PointPair& p : pairs) {
        const uint32_t a = uint32_t(submesh_of_vertex[p.first]), b = uint32_t(submesh_of_vertex[p.second]);
        p = a > b ? PointPair(a, b) : PointPair(b, a);
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

    // Greedy colouring in id order: each submesh takes the lowest pass no earlier neighbour has.
    size_t passes = 0;
    std::vector<uint8_t> taken;
    size_t k = 0;
    for (size_t s = 0; s < submesh_count; ++s) {
        pass_of_submesh[s] = -1;
        if (!chosen[s]) continue;
        taken.assign(passes + 1, 0);
        for (; k < pairs.size() && pairs[k].first == s; ++k) {
            const int32_t other = pass_of_submesh[pairs[k].second];
            if (other >= 0) taken[size_t(other)] = 1;
        }
        const size_t pass = size_t(std::find(taken.begin(), taken.end(), 0) - taken.begin());
        pass_of_submesh[s] = int32_t(pass);
        passes = std::max(passes, pass + 1);
    }
    return passes;
}

}  // namespace boxmarch
