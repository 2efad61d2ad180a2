// Connected components of a mesh through its edges and face corners (union-find: a disjoint-set
// forest with path halving, Tarjan and van Leeuwen 1984).
#include "boxmarch/boxmarch.h"
#include "internal.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

// Root of v, halving the path on the way so later finds stay short.
int32_t find_root(std::vector<int32_t>& parent, int32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

// Joins the sets of a and b; the smaller root wins, which keeps the forest shallow enough and
// makes the outcome independent of the order joins arrive in.
void unite(std::vector<int32_t>& parent, int32_t a, int32_t b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

// Numbers the sets of `parent` into submesh_of_vertex; returns how many there are. Roots are the
// lowest vertex of their set, so numbering roots in vertex order numbers submeshes by their
// lowest vertex.
size_t number_sets(int32_t* submesh_of_vertex, std::vector<int32_t>& parent) {
    size_t count = 0;
    for (size_t v = 0; v < parent.size(); ++v) {
        const int32_t root = find_root(parent, int32_t(v));
        submesh_of_vertex[v] = (root == int32_t(v)) ? int32_t(count++) : submesh_of_vertex[root];
    }
    return count;
}

}  // namespace

size_t find_submeshes(int32_t* submesh_of_vertex, const MeshView& mesh) {
    const size_t n = mesh.vertex_count;
    std::vector<int32_t> parent(n);
    for (size_t v = 0; v < n; ++v) parent[v] = int32_t(v);
    for (size_t e = 0; e < mesh.edge_count; ++e) unite(parent, mesh.edges[2 * e], mesh.edges[2 * e + 1]);
    size_t count = number_sets(submesh_of_vertex, parent);
    // Faces normally come with their edges, so their corners already share a submesh; checking
    // that is a cheap lookup, and only edge-less face data pays for joining corners.
    bool joined = true;
    for (size_t f = 0; f < mesh.face_count; ++f) {
        const int32_t* corners = mesh.corner_verts + mesh.face_starts[f];
        const int32_t first = submesh_of_vertex[corners[0]];
        for (int32_t c = 1; c < mesh.face_sizes[f]; ++c) joined &= submesh_of_vertex[corners[c]] == first;
    }
    if (joined) return count;
    for (size_t f = 0; f < mesh.face_count; ++f) {
        const int32_t* corners = mesh.corner_verts + mesh.face_starts[f];
        for (int32_t c = 1; c < mesh.face_sizes[f]; ++c) unite(parent, corners[0], corners[c]);
    }
    return number_sets(submesh_of_vertex, parent);
}

size_t face_starts_from_corner_edges(int32_t* face_starts, const int32_t* corner_verts, const int32_t* corner_edges,
                                     size_t corner_count, const int32_t* edges, size_t edge_count,
                                     size_t vertex_count) {
    const size_t bad_edge = first_out_of_range(corner_edges, corner_count, edge_count);
    const size_t bad_vertex = first_out_of_range(corner_verts, corner_count, vertex_count);
    if (bad_edge < corner_count || bad_vertex < corner_count)
        throw std::invalid_argument("corner " + std::to_string(std::min(bad_edge, bad_vertex)) + " names " +
                                    (bad_edge <= bad_vertex ? "an edge" : "a vertex") + " out of range");
    const size_t capacity = corner_count / 3 + 1;
    size_t count = 0, start = 0;
    if (corner_count) face_starts[count++] = 0;
    for (size_t c = 0; c + 1 < corner_count; ++c) {
        const int32_t a = edges[2 * size_t(corner_edges[c])], b = edges[2 * size_t(corner_edges[c]) + 1];
        const int32_t here = corner_verts[c], next = corner_verts[c + 1];
        const bool joined = (a == here && b == next) || (a == next && b == here);
        if (!joined || next == corner_verts[start]) {
            if (count == capacity) return count + 1;  // more faces than corners allow: not a valid mesh
            start = c + 1;
            face_starts[count++] = int32_t(start);
        }
    }
    return count;
}

void check_submesh_ids(const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count) {
    const size_t bad = first_out_of_range(submesh_of_vertex, vertex_count, submesh_count);
    if (bad < vertex_count)
        throw std::invalid_argument("submesh_of_vertex[" + std::to_string(bad) +
                                    "] = " + std::to_string(submesh_of_vertex[bad]) + " is outside 0.." +
                                    std::to_string(submesh_count) + "-1");
}

void group_by_submesh(uint32_t* offsets, uint32_t* items, const int32_t* submesh_of_item, size_t item_count,
                      size_t submesh_count) {
    const size_t bad = first_out_of_range(submesh_of_item, item_count, submesh_count);
    if (bad < item_count)
        throw std::invalid_argument("item " + std::to_string(bad) + " names submesh " +
                                    std::to_string(submesh_of_item[bad]) + ", outside 0.." +
                                    std::to_string(submesh_count) + "-1");
    const auto owner = [&](size_t i) { return submesh_of_item[i]; };
    if (count_by_owner(offsets, item_count, submesh_count, owner)) {
        // the common case (submeshes stored one after another): no scatter needed
        for (size_t i = 0; i < item_count; ++i) items[i] = uint32_t(i);
    } else {
        scatter_by_owner(items, offsets, item_count, submesh_count, owner);
    }
}

}  // namespace boxmarch
