// Plans for merging by distance inside each submesh with a merge that works on a whole vertex
// selection (Blender's own): select only vertices that have a partner in their own submesh, and
// put submeshes whose selected vertices come within the distance of each other into different
// passes, so one pass never merges across submeshes.
#include "boxmarch/boxmarch.h"
#include "spatial_hash.h"

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
