// Topology after merging vertices, as a host's weld (Blender's Merge by Distance) leaves it in the
// common case; the caller falls back to the host itself where the weld would split or dedupe faces.
#include "boxmarch/boxmarch.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

inline uint64_t edge_key(uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a; }

constexpr uint32_t kNone = UINT32_MAX;

void check_weld_input(const MeshView& mesh, const int32_t* target) {
    const size_t n = mesh.vertex_count;
    for (size_t v = 0; v < n; ++v)
        if (target[v] < 0 || size_t(target[v]) >= n || target[size_t(target[v])] != target[v])
            throw std::invalid_argument("target[" + std::to_string(v) + "] is not a surviving vertex");
    // The outputs hold corner_count corners: faces sharing corners (valid for validate_mesh, never
    // stored by Blender) could need more, so they are refused before anything is written.
    size_t corners_named = 0;
    for (size_t f = 0; f < mesh.face_count; ++f) corners_named += size_t(mesh.face_sizes[f]);
    if (corners_named > mesh.corner_count)
        throw std::invalid_argument("faces name " + std::to_string(corners_named) + " corners but there are " +
                                    std::to_string(mesh.corner_count) + ": faces overlap");
}

// Old vertex -> new vertex: survivors keep their order, the others take their target's number.
struct VertexImage {
    const int32_t* target;
    std::vector<int32_t> new_index;  // of the survivors, -1 for the others
    uint32_t operator()(int32_t v) const { return uint32_t(new_index[size_t(target[v])]); }
};

VertexImage keep_survivors(size_t n, const int32_t* target, const WeldOutput& out, WeldCounts& counts) {
    VertexImage image{target, std::vector<int32_t>(n, -1)};
    for (size_t v = 0; v < n; ++v)
        if (target[v] == int32_t(v)) {
            image.new_index[v] = int32_t(counts.vertices);
            out.vertex_source[counts.vertices++] = int32_t(v);
        }
    return image;
}

// Edges: distinct images of non-collapsing old edges, the first old edge of each. Returns each
// old edge's new edge (kNone for the collapsed). Only edges at a welded vertex (merged away, or
// merged into) can meet another edge's image; the others keep theirs alone and need no sorting.
std::vector<uint32_t> weld_edges(const MeshView& mesh, const VertexImage& image, const WeldOutput& out,
                                 WeldCounts& counts) {
    const size_t n = mesh.vertex_count;
    std::vector<uint8_t> welded_old(n, 0);
    for (size_t v = 0; v < n; ++v)
        if (image.target[v] != int32_t(v)) welded_old[v] = welded_old[size_t(image.target[v])] = 1;
    std::vector<uint32_t> first_of(mesh.edge_count, kNone);  // the old edge whose image each keeps
    std::vector<std::pair<uint64_t, uint32_t>> keyed;
    for (size_t e = 0; e < mesh.edge_count; ++e) {
        const int32_t u = mesh.edges[2 * e], w = mesh.edges[2 * e + 1];
        const uint32_t a = image(u), b = image(w);
        if (a == b) continue;  // collapses
        if (welded_old[size_t(u)] || welded_old[size_t(w)])
            keyed.emplace_back(edge_key(a, b), uint32_t(e));
        else
            first_of[e] = uint32_t(e);
    }
    std::sort(keyed.begin(), keyed.end());
    for (size_t k = 0, first = 0; k < keyed.size(); ++k) {
        if (keyed[k].first != keyed[first].first) first = k;
        first_of[keyed[k].second] = keyed[first].second;
    }
    std::vector<uint32_t> new_of_old(mesh.edge_count, kNone);
    for (size_t e = 0; e < mesh.edge_count; ++e)
        if (first_of[e] == uint32_t(e)) {
            const uint32_t a = image(mesh.edges[2 * e]), b = image(mesh.edges[2 * e + 1]);
            out.edge_source[counts.edges] = int32_t(e);
            out.edges[2 * counts.edges] = int32_t(a);
            out.edges[2 * counts.edges + 1] = int32_t(b);
            new_of_old[e] = uint32_t(counts.edges++);
        }
    for (size_t e = 0; e < mesh.edge_count; ++e)
        if (first_of[e] != kNone) new_of_old[e] = new_of_old[first_of[e]];
    return new_of_old;
}

// Faces: drop a corner whose vertex equals the next corner's; drop faces under 3 corners.
// Returns, per new face, whether any of its old vertices merged away.
std::vector<uint8_t> weld_faces(const MeshView& mesh, const VertexImage& image, const WeldOutput& out,
                                WeldCounts& counts) {
    std::vector<uint32_t> ring;
    std::vector<uint8_t> touched_face;
    for (size_t f = 0; f < mesh.face_count; ++f) {
        const int32_t start = mesh.face_starts[f], size = mesh.face_sizes[f];
        ring.clear();
        bool touched = false;
        for (int32_t k = 0; k < size; ++k) {
            const int32_t v = mesh.corner_verts[start + k];
            const int32_t next = mesh.corner_verts[start + (k + 1) % size];
            touched = touched || image.target[v] != v;
            if (image(v) != image(next)) ring.push_back(uint32_t(start + k));
        }
        if (ring.size() < 3) continue;
        const int32_t first = int32_t(counts.corners);
        for (uint32_t c : ring) {
            const uint32_t v = image(mesh.corner_verts[c]);
            for (int32_t k = first; k < int32_t(counts.corners); ++k)
                if (out.corner_verts[k] == int32_t(v)) counts.incomplete = true;  // would be split
            out.corner_source[counts.corners] = int32_t(c);
            out.corner_verts[counts.corners++] = int32_t(v);
        }
        out.face_source[counts.faces] = int32_t(f);
        out.face_starts[counts.faces++] = first;
        touched_face.push_back(touched);
    }
    return touched_face;
}

size_t face_end(const WeldOutput& out, const WeldCounts& counts, size_t f) {
    return f + 1 < counts.faces ? size_t(out.face_starts[f + 1]) : counts.corners;
}

// Each face corner's edge, to the next corner, from the old corner edges: corners dropped after c
// merged into the next kept corner, so the old edge from c to its next corner has the new edge's
// image.
void corner_edges_from_old(const MeshView& mesh, const int32_t* corner_edges, const std::vector<uint32_t>& new_of_old,
                           const WeldOutput& out, WeldCounts& counts) {
    for (size_t c = 0; c < counts.corners; ++c) {
        const int32_t old = corner_edges[out.corner_source[c]];
        if (old < 0 || size_t(old) >= mesh.edge_count || new_of_old[size_t(old)] == kNone) {
            counts.incomplete = true;
            out.corner_edges[c] = 0;
        } else
            out.corner_edges[c] = int32_t(new_of_old[size_t(old)]);
    }
}

// Each face corner's edge, to the next corner, looked up among the new edges by their vertices.
void corner_edges_by_lookup(const WeldOutput& out, WeldCounts& counts) {
    std::vector<std::pair<uint64_t, uint32_t>> new_edge_of_key(counts.edges);
    for (size_t k = 0; k < counts.edges; ++k)
        new_edge_of_key[k] = {edge_key(uint32_t(out.edges[2 * k]), uint32_t(out.edges[2 * k + 1])), uint32_t(k)};
    std::sort(new_edge_of_key.begin(), new_edge_of_key.end());
    for (size_t f = 0; f < counts.faces; ++f) {
        const size_t start = size_t(out.face_starts[f]);
        const size_t end = face_end(out, counts, f);
        for (size_t c = start; c < end; ++c) {
            const uint32_t a = uint32_t(out.corner_verts[c]);
            const uint32_t b = uint32_t(out.corner_verts[c + 1 < end ? c + 1 : start]);
            const uint64_t key = edge_key(a, b);
            auto it = std::lower_bound(new_edge_of_key.begin(), new_edge_of_key.end(), std::make_pair(key, 0u));
            if (it == new_edge_of_key.end() || it->first != key) {
                counts.incomplete = true;  // a face edge with no edge: not a valid Blender mesh
                out.corner_edges[c] = 0;
            } else
                out.corner_edges[c] = int32_t(it->second);
        }
    }
}

// Two faces over the same vertices where one of them changed: Blender's weld removes one, so the
// result is flagged incomplete. Such a pair shares a vertex that other vertices merged into, so
// only faces holding one are compared.
void flag_doubled_faces(size_t n, const VertexImage& image, const std::vector<uint8_t>& touched_face,
                        const WeldOutput& out, WeldCounts& counts) {
    std::vector<uint8_t> welded(counts.vertices, 0);
    for (size_t v = 0; v < n; ++v)
        if (image.target[v] != int32_t(v)) welded[size_t(image.new_index[size_t(image.target[v])])] = 1;
    std::vector<std::pair<uint64_t, uint32_t>> face_keys;
    std::vector<int32_t> sorted;
    auto sorted_face = [&](size_t f, std::vector<int32_t>& vs) {
        vs.assign(out.corner_verts + out.face_starts[f], out.corner_verts + face_end(out, counts, f));
        std::sort(vs.begin(), vs.end());
    };
    for (size_t f = 0; f < counts.faces; ++f) {
        const size_t start = size_t(out.face_starts[f]);
        const size_t end = face_end(out, counts, f);
        bool holds_welded = false;
        for (size_t c = start; c < end && !holds_welded; ++c) holds_welded = welded[size_t(out.corner_verts[c])];
        if (!holds_welded) continue;
        sorted_face(f, sorted);
        uint64_t h = 1469598103934665603ull ^ sorted.size();
        for (int32_t v : sorted) h = (h ^ uint64_t(uint32_t(v))) * 1099511628211ull;
        face_keys.emplace_back(h, uint32_t(f));
    }
    std::sort(face_keys.begin(), face_keys.end());
    std::vector<int32_t> other;
    for (size_t k = 1; k < face_keys.size(); ++k)
        if (face_keys[k].first == face_keys[k - 1].first) {
            const uint32_t a = face_keys[k - 1].second, b = face_keys[k].second;
            if (!touched_face[a] && !touched_face[b]) continue;  // doubled before: Blender leaves it
            sorted_face(a, sorted);
            sorted_face(b, other);
            if (sorted == other) counts.incomplete = true;
        }
}

}  // namespace

WeldCounts weld_topology(const MeshView& mesh, const int32_t* corner_edges, const int32_t* target,
                         const WeldOutput& out) {
    check_weld_input(mesh, target);
    WeldCounts counts;
    const VertexImage image = keep_survivors(mesh.vertex_count, target, out, counts);
    const std::vector<uint32_t> new_of_old = weld_edges(mesh, image, out, counts);
    const std::vector<uint8_t> touched_face = weld_faces(mesh, image, out, counts);
    if (corner_edges)
        corner_edges_from_old(mesh, corner_edges, new_of_old, out, counts);
    else
        corner_edges_by_lookup(out, counts);
    flag_doubled_faces(mesh.vertex_count, image, touched_face, out, counts);
    return counts;
}

}  // namespace boxmarch
