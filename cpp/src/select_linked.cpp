// Selection flood fills over whole submeshes: through edges only, or also across to other
// submeshes whose vertices come within epsilon.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <vector>

namespace boxmarch {

namespace {

// Writes the vertex mask of the marked submeshes; returns how many are marked.
size_t expand_submeshes(uint8_t* out_selected, const std::vector<uint8_t>& marked,
                        const int32_t* submesh_of_vertex, size_t vertex_count) {
    for (size_t v = 0; v < vertex_count; ++v) out_selected[v] = marked[size_t(submesh_of_vertex[v])];
    size_t count = 0;
    for (uint8_t m : marked) count += m;
    return count;
}

std::vector<uint8_t> touched_submeshes(const uint8_t* selected, const int32_t* submesh_of_vertex,
                                       size_t vertex_count, size_t submesh_count) {
    std::vector<uint8_t> marked(submesh_count, 0);
    for (size_t v = 0; v < vertex_count; ++v)
        if (selected[v]) marked[size_t(submesh_of_vertex[v])] = 1;
    return marked;
}

}  // namespace

size_t select_linked_submeshes(uint8_t* out_selected, const uint8_t* selected,
                               const int32_t* submesh_of_vertex, size_t vertex_count,
                               size_t submesh_count) {
    const std::vector<uint8_t> marked = touched_submeshes(selected, submesh_of_vertex, vertex_count, submesh_count);
    return expand_submeshes(out_selected, marked, submesh_of_vertex, vertex_count);
}

size_t select_linked_across(uint8_t* out_selected, const uint8_t* selected, const float* positions,
                            const int32_t* submesh_of_vertex, size_t vertex_count,
                            size_t submesh_count, double epsilon, int threads) {
    check_radius(epsilon, "epsilon");
    check_finite_positions(positions, vertex_count);
    std::vector<uint8_t> marked = touched_submeshes(selected, submesh_of_vertex, vertex_count, submesh_count);
    const std::vector<PointPair> pairs = close_pairs(positions, vertex_count, epsilon, submesh_of_vertex, threads);

    std::vector<PointPair> links(pairs.size());
    for (size_t k = 0; k < pairs.size(); ++k)
        links[k] = PointPair(uint32_t(submesh_of_vertex[pairs[k].first]), uint32_t(submesh_of_vertex[pairs[k].second]));
    // Submeshes linked by close vertices form one region; a region the selection touches is
    // selected whole.
    std::vector<uint32_t> region;
    const size_t regions = label_components(region, submesh_count, links);
    std::vector<uint8_t> region_marked(regions, 0);
    for (size_t s = 0; s < submesh_count; ++s)
        if (marked[s]) region_marked[region[s]] = 1;
    for (size_t s = 0; s < submesh_count; ++s) marked[s] = region_marked[region[s]];
    return expand_submeshes(out_selected, marked, submesh_of_vertex, vertex_count);
}

}  // namespace boxmarch
