// UV islands packed in rows sorted by the height of their submesh: the highest at the top of the
// unit square, one uniform scale for all, the largest whose row layout fits.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

constexpr double kUvEqual = 1e-6;  // corners closer than this in UV share the island

struct Unit {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    double height = -INFINITY;
    uint32_t first_face = UINT32_MAX;
    double x = 0.0, y = 0.0;  // placed lower-left corner
};

void grow(Unit& u, const Unit& other) {
    for (int d = 0; d < 2; ++d) {
        u.lo[d] = std::min(u.lo[d], other.lo[d]);
        u.hi[d] = std::max(u.hi[d], other.hi[d]);
    }
    u.height = std::max(u.height, other.height);
    u.first_face = std::min(u.first_face, other.first_face);
}

// Rows of units of widths w[k] and heights h[k] (in placing order, at scale 1) at scale s;
// writes each unit's lower-left corner into x[k], y[k] when they are not null. Returns the
// number of rows, or 0 when the layout does not fit the unit square.
size_t layout(const std::vector<double>& w, const std::vector<double>& h, double s, double pad, size_t max_per_row,
              double* x_out, double* y_out) {
    double x = pad, top = 1.0 - pad, row_height = 0.0;
    size_t in_row = 0, rows = 0, row_first = 0;
    auto close_row = [&](size_t end) {
        if (y_out)
            for (size_t k = row_first; k < end; ++k) y_out[k] = top - row_height;
        top -= row_height + pad;
        ++rows;
    };
    const size_t n = w.size();
    for (size_t k = 0; k < n; ++k) {
        const double wk = w[k] * s;
        if (in_row > 0 && ((max_per_row && in_row == max_per_row) || x + wk + pad > 1.0)) {
            close_row(k);
            if (top < 0.0) return 0;  // already below the square: no need to go on
            x = pad;
            row_height = 0.0;
            in_row = 0;
            row_first = k;
        }
        if (x + wk + pad > 1.0) return 0;
        if (x_out) x_out[k] = x;
        x += wk + pad;
        row_height = std::max(row_height, h[k] * s);
        ++in_row;
    }
    close_row(n);
    return top >= -1e-12 ? rows : 0;
}

// The selected faces, after checking the padding, the UVs of those faces and every height.
std::vector<uint32_t> checked_selected_faces(const float* corner_uv, const MeshView& mesh, const uint8_t* face_mask,
                                             const float* vertex_height, double pad) {
    if (!std::isfinite(pad) || pad < 0.0 || pad >= 0.5)
        throw std::invalid_argument("padding must be in [0, 0.5), got " + std::to_string(pad));
    std::vector<uint32_t> faces;
    for (size_t f = 0; f < mesh.face_count; ++f)
        if (!face_mask || face_mask[f]) faces.push_back(uint32_t(f));
    if (faces.empty()) throw std::invalid_argument("no face is selected");
    for (uint32_t f : faces)
        for (int32_t c = mesh.face_starts[f]; c < mesh.face_starts[f] + mesh.face_sizes[f]; ++c)
            if (!std::isfinite(corner_uv[2 * size_t(c)]) || !std::isfinite(corner_uv[2 * size_t(c) + 1]))
                throw std::invalid_argument("corner " + std::to_string(c) + " has a NaN or infinite UV");
    for (size_t v = 0; v < mesh.vertex_count; ++v)
        if (!std::isfinite(vertex_height[v]))
            throw std::invalid_argument("vertex " + std::to_string(v) + " has a NaN or infinite height");
    return faces;
}

// The height of every submesh: the centre of its vertices' height range.
std::vector<double> submesh_heights(const MeshView& mesh, const float* vertex_height, const int32_t* submesh_of_vertex,
                                    size_t submesh_count) {
    std::vector<double> low(submesh_count, INFINITY), high(submesh_count, -INFINITY);
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
        const size_t s = size_t(submesh_of_vertex[v]);
        low[s] = std::min(low[s], double(vertex_height[v]));
        high[s] = std::max(high[s], double(vertex_height[v]));
    }
    for (size_t s = 0; s < submesh_count; ++s) low[s] = 0.5 * (low[s] + high[s]);
    return low;
}

// Islands: the selected faces (numbered 0.. in `faces`) linked where two corners share a vertex
// and a UV; writes island_of_face and returns each island's UV bounds, lowest face and height.
std::vector<Unit> find_islands(std::vector<uint32_t>& island_of_face, const float* corner_uv, const MeshView& mesh,
                               const std::vector<uint32_t>& faces, const std::vector<double>& heights,
                               const int32_t* submesh_of_vertex) {
    // Corners of selected faces grouped by vertex (CSR), compared within each vertex.
    std::vector<uint32_t> vstart(mesh.vertex_count + 1, 0);
    for (uint32_t f : faces)
        for (int32_t c = mesh.face_starts[f]; c < mesh.face_starts[f] + mesh.face_sizes[f]; ++c)
            ++vstart[size_t(mesh.corner_verts[c]) + 1];
    for (size_t v = 0; v < mesh.vertex_count; ++v) vstart[v + 1] += vstart[v];
    std::vector<uint32_t> cursor(vstart.begin(), vstart.end() - 1), vcorner(vstart.back()), vface(vstart.back());
    for (uint32_t i = 0; i < faces.size(); ++i)
        for (int32_t c = mesh.face_starts[faces[i]]; c < mesh.face_starts[faces[i]] + mesh.face_sizes[faces[i]]; ++c) {
            const uint32_t slot = cursor[size_t(mesh.corner_verts[c])]++;
            vcorner[slot] = uint32_t(c);
            vface[slot] = i;
        }
    std::vector<PointPair> links;
    for (size_t v = 0; v < mesh.vertex_count; ++v)
        for (uint32_t a = vstart[v]; a < vstart[v + 1]; ++a)
            for (uint32_t b = a + 1; b < vstart[v + 1]; ++b) {
                const float* ua = corner_uv + 2 * size_t(vcorner[a]);
                const float* ub = corner_uv + 2 * size_t(vcorner[b]);
                if (vface[a] != vface[b] && std::abs(double(ua[0]) - ub[0]) <= kUvEqual &&
                    std::abs(double(ua[1]) - ub[1]) <= kUvEqual)
                    links.emplace_back(vface[a], vface[b]);
            }
    std::vector<Unit> islands(label_components(island_of_face, faces.size(), links));
    for (uint32_t i = 0; i < faces.size(); ++i) {
        Unit& u = islands[island_of_face[i]];
        const int32_t start = mesh.face_starts[faces[i]];
        for (int32_t c = start; c < start + mesh.face_sizes[faces[i]]; ++c)
            for (int d = 0; d < 2; ++d) {
                u.lo[d] = std::min(u.lo[d], double(corner_uv[2 * size_t(c) + d]));
                u.hi[d] = std::max(u.hi[d], double(corner_uv[2 * size_t(c) + d]));
            }
        if (u.first_face == UINT32_MAX) {  // faces come in index order: the first is the lowest
            u.first_face = faces[i];
            u.height = heights[size_t(submesh_of_vertex[mesh.corner_verts[start]])];
        }
    }
    return islands;
}

// Sets of islands whose UV bounds overlap (with area), by a sweep along u; writes the set of
// each island into unit_of_island and returns the number of sets.
size_t overlapping_sets(std::vector<uint32_t>& unit_of_island, const std::vector<Unit>& islands) {
    const size_t island_count = islands.size();
    std::vector<uint32_t> by_left(island_count);
    for (uint32_t k = 0; k < island_count; ++k) by_left[k] = k;
    std::sort(by_left.begin(), by_left.end(), [&](uint32_t a, uint32_t b) {
        const Unit &p = islands[a], &q = islands[b];
        if (p.lo[0] != q.lo[0]) return p.lo[0] < q.lo[0];
        if (p.lo[1] != q.lo[1]) return p.lo[1] < q.lo[1];
        if (p.hi[0] != q.hi[0]) return p.hi[0] < q.hi[0];
        if (p.hi[1] != q.hi[1]) return p.hi[1] < q.hi[1];
        return a < b;
    });
    // Identical bounds are linked to their first copy and never swept twice, so stacks of
    // identical layouts stay linear.
    std::vector<PointPair> overlaps;
    std::vector<uint32_t> active;
    for (size_t k = 0; k < island_count; ++k) {
        const Unit& q = islands[by_left[k]];
        if (k > 0) {
            const Unit& p = islands[by_left[k - 1]];
            if (p.lo[0] == q.lo[0] && p.lo[1] == q.lo[1] && p.hi[0] == q.hi[0] && p.hi[1] == q.hi[1]) {
                if (q.hi[0] > q.lo[0] && q.hi[1] > q.lo[1]) overlaps.emplace_back(by_left[k - 1], by_left[k]);
                continue;
            }
        }
        size_t kept = 0;
        for (uint32_t a : active) {
            const Unit& p = islands[a];
            if (p.hi[0] <= q.lo[0]) continue;  // ends before q starts: never overlaps again
            active[kept++] = a;
            if (p.lo[1] < q.hi[1] && q.lo[1] < p.hi[1] && p.lo[0] < q.hi[0]) overlaps.emplace_back(a, by_left[k]);
        }
        active.resize(kept);
        active.push_back(by_left[k]);
    }
    return label_components(unit_of_island, island_count, overlaps);
}

// Placing order of the units: highest first, ties by lowest face. Sorting compact keys (not
// indices that reach into the units) keeps the sort in cache.
std::vector<uint32_t> placing_order(const std::vector<Unit>& units) {
    struct Key {
        double height;
        uint32_t first_face, unit;
        bool operator<(const Key& o) const {
            return height != o.height ? height > o.height : first_face < o.first_face;
        }
    };
    std::vector<Key> keys(units.size());
    for (uint32_t k = 0; k < units.size(); ++k) keys[k] = Key{units[k].height, units[k].first_face, k};
    std::sort(keys.begin(), keys.end());
    std::vector<uint32_t> order(units.size());
    for (size_t k = 0; k < keys.size(); ++k) order[k] = keys[k].unit;
    return order;
}

// The largest uniform scale whose layout of units w x h (in placing order) fits the square, by
// bisection below the scale at which the largest unit alone spans the square and the one at
// which the units' area fills it. Throws when the padding alone leaves no room.
double largest_fitting_scale(const std::vector<double>& w, const std::vector<double>& h, double pad,
                             size_t max_per_row) {
    double largest = 0.0, area = 0.0;
    for (size_t k = 0; k < w.size(); ++k) {
        largest = std::max({largest, w[k], h[k]});
        area += w[k] * h[k];
    }
    if (!layout(w, h, 0.0, pad, max_per_row, nullptr, nullptr))
        throw std::invalid_argument("padding " + std::to_string(pad) + " leaves no room for " +
                                    std::to_string(w.size()) + " islands in the unit square");
    if (largest <= 0.0) return 1.0;
    double fails = (1.0 - 2.0 * pad) / largest;
    if (area > 0.0) fails = std::min(fails, std::sqrt(1.0 / area));
    double fits = 0.0;
    if (layout(w, h, fails, pad, max_per_row, nullptr, nullptr)) return fails;
    for (int it = 0; it < 80 && fails - fits > fails * 1e-5; ++it) {
        const double mid = 0.5 * (fits + fails);
        (layout(w, h, mid, pad, max_per_row, nullptr, nullptr) ? fits : fails) = mid;
    }
    return fits;
}

}  // namespace

PackUvReport pack_uv_by_height(float* corner_uv, const MeshView& mesh, const uint8_t* face_mask,
                               const float* vertex_height, const int32_t* submesh_of_vertex, size_t submesh_count,
                               const PackUvOptions& options) {
    check_submesh_ids(submesh_of_vertex, mesh.vertex_count, submesh_count);
    const double pad = options.padding;
    const std::vector<uint32_t> faces = checked_selected_faces(corner_uv, mesh, face_mask, vertex_height, pad);
    const std::vector<double> heights = submesh_heights(mesh, vertex_height, submesh_of_vertex, submesh_count);
    std::vector<uint32_t> island_of_face;
    const std::vector<Unit> islands = find_islands(island_of_face, corner_uv, mesh, faces, heights, submesh_of_vertex);
    const size_t island_count = islands.size();

    // Units that move as one: islands, or sets of islands whose UV bounds overlap.
    std::vector<uint32_t> unit_of_island(island_count);
    std::vector<Unit> units;
    if (options.lock_overlapping) {
        units.resize(overlapping_sets(unit_of_island, islands));
    } else {
        for (uint32_t k = 0; k < island_count; ++k) unit_of_island[k] = k;
        units.resize(island_count);
    }
    for (uint32_t k = 0; k < island_count; ++k) grow(units[unit_of_island[k]], islands[k]);

    // Sizes in placing order, contiguous: the bisection runs the layout a few dozen times.
    const std::vector<uint32_t> order = placing_order(units);
    const size_t unit_count = units.size();
    std::vector<double> w(unit_count), h(unit_count);
    for (size_t k = 0; k < unit_count; ++k) {
        w[k] = units[order[k]].hi[0] - units[order[k]].lo[0];
        h[k] = units[order[k]].hi[1] - units[order[k]].lo[1];
    }
    const double scale = largest_fitting_scale(w, h, pad, options.max_per_row);
    std::vector<double> x(unit_count), y(unit_count);
    PackUvReport report;
    report.rows = layout(w, h, scale, pad, options.max_per_row, x.data(), y.data());
    for (size_t k = 0; k < unit_count; ++k) {
        units[order[k]].x = x[k];
        units[order[k]].y = y[k];
    }
    report.islands = island_count;
    report.groups = unit_count;
    report.scale = scale;

    for (uint32_t i = 0; i < faces.size(); ++i) {
        const Unit& u = units[unit_of_island[island_of_face[i]]];
        for (int32_t c = mesh.face_starts[faces[i]]; c < mesh.face_starts[faces[i]] + mesh.face_sizes[faces[i]]; ++c) {
            float* uv = corner_uv + 2 * size_t(c);
            // Rounding to float may step a hair past the square's edge: clamp that hair.
            uv[0] = float(std::clamp((double(uv[0]) - u.lo[0]) * scale + u.x, 0.0, 1.0));
            uv[1] = float(std::clamp((double(uv[1]) - u.lo[1]) * scale + u.y, 0.0, 1.0));
        }
    }
    return report;
}

}  // namespace boxmarch
