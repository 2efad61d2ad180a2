// Merge by distance inside each submesh. Nothing here lists pairs of vertices: a dense cluster
// (every vertex at one point) would make that quadratic. Vertices with a partner are found by a
// search that stops at the first one; clusters are gathered by one radius search per unassigned
// vertex over a grid from which every assigned vertex is removed; the plan for Blender's own
// merge colours submeshes as it meets them.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <cmath>
#include <algorithm>
#include <vector>

namespace boxmarch {

namespace {

// The vertices of chosen submeshes as groups for the searches (-1: left out).
std::vector<int32_t> chosen_groups(const int32_t* submesh_of_vertex, size_t vertex_count, const uint8_t* chosen) {
    std::vector<int32_t> group(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v)
        group[v] = chosen[size_t(submesh_of_vertex[v])] ? submesh_of_vertex[v] : -1;
    return group;
}

std::vector<uint32_t> marked_vertices(const std::vector<uint8_t>& mark) {
    std::vector<uint32_t> list;
    for (size_t v = 0; v < mark.size(); ++v)
        if (mark[v]) list.push_back(uint32_t(v));
    return list;
}

}  // namespace

// Plans for merging by distance inside each submesh with a merge that works on a whole vertex
// selection (Blender's own): select only vertices that have a partner in their own submesh, and
// put submeshes whose selected vertices come within the distance of each other into different
// passes, so one pass never merges across submeshes.
size_t merge_passes(int32_t* pass_of_vertex, const float* positions, const int32_t* submesh_of_vertex,
                    size_t vertex_count, size_t submesh_count, const uint8_t* chosen, double distance, int threads) {
    check_submesh_ids(submesh_of_vertex, vertex_count, submesh_count);
    check_radius(distance, "distance");
    check_finite_positions(positions, vertex_count);
    const double radius = distance * (1 + 1e-6);
    const std::vector<int32_t> group = chosen_groups(submesh_of_vertex, vertex_count, chosen);
    std::vector<uint8_t> candidate(vertex_count);
    mark_points_with_partner(candidate.data(), positions, vertex_count, radius, group.data(), threads);
    const std::vector<uint32_t> candidates = marked_vertices(candidate);

    // Candidates by submesh (ascending ids), and a grid of them whose buckets hold each
    // submesh's items as one run, so a search skips a submesh it has nothing to learn from.
    std::vector<uint32_t> offsets(submesh_count + 1), by_submesh(candidates.size());
    count_by_owner(offsets.data(), candidates.size(), submesh_count,
                   [&](size_t k) { return submesh_of_vertex[candidates[k]]; });
    scatter_by_owner(by_submesh.data(), offsets.data(), candidates.size(), submesh_count,
                     [&](size_t k) { return submesh_of_vertex[candidates[k]]; });
    Grid<float> g;
    build_grid(g, positions, candidates, radius, nullptr);
    std::vector<uint32_t> run_end(g.items.size());
    {
        std::vector<uint32_t> order;
        std::vector<float> moved;
        for (size_t b = 0; b + 1 < g.bucket_start.size(); ++b) {
            const uint32_t first = g.bucket_start[b], last = g.bucket_start[b + 1];
            if (last - first > 1) {
                order.assign(g.items.begin() + first, g.items.begin() + last);
                std::stable_sort(order.begin(), order.end(),
                                 [&](uint32_t x, uint32_t y) { return submesh_of_vertex[x] < submesh_of_vertex[y]; });
                for (uint32_t m = first; m < last; ++m) {
                    g.items[m] = order[m - first];
                    for (int d = 0; d < 3; ++d)
                        g.sorted_positions[3 * size_t(m) + d] = positions[3 * size_t(order[m - first]) + d];
                }
            }
            for (uint32_t m = last; m > first; --m)
                run_end[m - 1] = (m < last && submesh_of_vertex[g.items[m]] == submesh_of_vertex[g.items[m - 1]])
                                         ? run_end[m]
                                         : m;
        }
    }

    // Greedy colouring in id order: each submesh takes the lowest pass no earlier submesh within
    // reach of its candidates has.
    std::vector<int32_t> pass_of_submesh(submesh_count, -1);
    const double r2 = radius * radius;
    size_t passes = 0;
    std::vector<uint8_t> taken;
    uint64_t buckets[27];
    for (size_t s = 0; s < submesh_count; ++s) {
        if (offsets[s] == offsets[s + 1]) continue;
        taken.assign(passes + 1, 0);
        for (uint32_t k = offsets[s]; k < offsets[s + 1]; ++k) {
            const float* q = positions + 3 * size_t(candidates[by_submesh[k]]);
            const double p[3] = {q[0], q[1], q[2]};
            const int nb = near_buckets(g, p, radius, 0, buckets);
            for (int bq = 0; bq < nb; ++bq) {
                for (uint32_t m = g.bucket_start[buckets[bq]], end = g.bucket_start[buckets[bq] + 1]; m < end;) {
                    const size_t other = size_t(submesh_of_vertex[g.items[m]]);
                    // A later submesh (or this one) takes its turn later; a pass already taken
                    // teaches nothing more: skip the run.
                    if (other >= s || taken[size_t(pass_of_submesh[other])]) {
                        m = run_end[m];
                    } else if (distance2(g, p, m) <= r2) {
                        taken[size_t(pass_of_submesh[other])] = 1;
                        m = run_end[m];
                    } else {
                        ++m;
                    }
                }
            }
        }
        const size_t pass = size_t(std::find(taken.begin(), taken.end(), 0) - taken.begin());
        pass_of_submesh[s] = int32_t(pass);
        passes = std::max(passes, pass + 1);
    }
    for (size_t v = 0; v < vertex_count; ++v)
        pass_of_vertex[v] = candidate[v] ? pass_of_submesh[size_t(submesh_of_vertex[v])] : -1;
    return passes;
}

size_t merge_targets(int32_t* target, float* merged_positions, const float* positions, const int32_t* submesh_of_vertex,
                     size_t vertex_count, size_t submesh_count, const uint8_t* chosen, double distance, int threads) {
    check_submesh_ids(submesh_of_vertex, vertex_count, submesh_count);
    check_radius(distance, "distance");
    check_finite_positions(positions, vertex_count);
    (void)submesh_count;
    const std::vector<int32_t> group = chosen_groups(submesh_of_vertex, vertex_count, chosen);
    // Only vertices with a partner can join a cluster: the grid holds them alone, keyed by
    // submesh, and loses each vertex as soon as a cluster takes it.
    std::vector<uint8_t> candidate(vertex_count);
    mark_points_with_partner(candidate.data(), positions, vertex_count, distance, group.data(), threads);
    const std::vector<uint32_t> candidates = marked_vertices(candidate);
    std::vector<uint8_t>().swap(candidate);
    Grid<float> g;
    build_grid(g, positions, candidates, distance, submesh_of_vertex);
    g.bucket_end.assign(g.bucket_start.begin() + 1, g.bucket_start.end());
    std::vector<uint32_t> slot_of(vertex_count, UINT32_MAX), bucket_of_slot(g.items.size());
    for (uint32_t m = 0; m < g.items.size(); ++m) slot_of[g.items[m]] = m;
    for (size_t b = 0; b + 1 < g.bucket_start.size(); ++b)
        std::fill(bucket_of_slot.begin() + g.bucket_start[b], bucket_of_slot.begin() + g.bucket_start[b + 1],
                  uint32_t(b));
    auto remove = [&](uint32_t v) {
        const uint32_t m = slot_of[v], b = bucket_of_slot[m], last = --g.bucket_end[b];
        const uint32_t w = g.items[last];
        std::swap(g.items[m], g.items[last]);
        for (int d = 0; d < 3; ++d)
            std::swap(g.sorted_positions[3 * size_t(m) + d], g.sorted_positions[3 * size_t(last) + d]);
        slot_of[w] = m;
        slot_of[v] = last;
    };

    std::copy(positions, positions + 3 * vertex_count, merged_positions);
    for (size_t v = 0; v < vertex_count; ++v) target[v] = -1;
    const double r2 = distance * distance;
    size_t merged = 0;
    std::vector<uint32_t> members;
    for (size_t v = 0; v < vertex_count; ++v) {
        if (target[v] >= 0) continue;
        target[v] = int32_t(v);
        if (slot_of[v] == UINT32_MAX) continue;  // no partner
        // Every unassigned vertex of its submesh within the distance: exactly the live items.
        const float* q = positions + 3 * v;
        const double p[3] = {q[0], q[1], q[2]};
        const int32_t sv = submesh_of_vertex[v];
        members.assign(1, uint32_t(v));
        visit_near(g, p, distance, sv, [&](uint32_t m) {
            const uint32_t j = g.items[m];
            if (j != v && submesh_of_vertex[j] == sv && distance2(g, p, m) <= r2) members.push_back(j);
            return false;
        });
        for (uint32_t m : members) remove(m);
        if (members.size() == 1) continue;
        std::sort(members.begin() + 1, members.end());
        double centroid[3] = {0, 0, 0};
        for (uint32_t m : members)
            for (int d = 0; d < 3; ++d) centroid[d] += positions[3 * size_t(m) + d];
        for (double& c : centroid) c /= double(members.size());
        uint32_t chosen_target = members[0];
        if (members.size() > 2) {
            double best = INFINITY;
            for (uint32_t m : members) {
                double d2 = 0;
                for (int d = 0; d < 3; ++d)
                    d2 += (positions[3 * size_t(m) + d] - centroid[d]) * (positions[3 * size_t(m) + d] - centroid[d]);
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
