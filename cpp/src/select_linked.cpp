// Selection flood fills over whole submeshes: through edges only, or also across to other
// submeshes whose vertices come within epsilon.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace boxmarch {

namespace {

// Writes the vertex mask of the marked submeshes; returns how many are marked.
size_t expand_submeshes(uint8_t* out_selected, const std::vector<uint8_t>& marked, const int32_t* submesh_of_vertex,
                        size_t vertex_count) {
    for (size_t v = 0; v < vertex_count; ++v) out_selected[v] = marked[size_t(submesh_of_vertex[v])];
    size_t count = 0;
    for (uint8_t m : marked) count += m;
    return count;
}

std::vector<uint8_t> touched_submeshes(const uint8_t* selected, const int32_t* submesh_of_vertex, size_t vertex_count,
                                       size_t submesh_count) {
    std::vector<uint8_t> marked(submesh_count, 0);
    for (size_t v = 0; v < vertex_count; ++v)
        if (selected[v]) marked[size_t(submesh_of_vertex[v])] = 1;
    return marked;
}

}  // namespace

size_t select_linked_submeshes(uint8_t* out_selected, const uint8_t* selected, const int32_t* submesh_of_vertex,
                               size_t vertex_count, size_t submesh_count) {
    check_submesh_ids(submesh_of_vertex, vertex_count, submesh_count);
    const std::vector<uint8_t> marked = touched_submeshes(selected, submesh_of_vertex, vertex_count, submesh_count);
    return expand_submeshes(out_selected, marked, submesh_of_vertex, vertex_count);
}

namespace {

// Sparse points: one radius search per point (partners of higher index), each thread joining the
// submeshes it links in a forest of its own (a pair inside one set is not even measured twice
// over), and the forests joined at the end. Memory: one forest per thread, never a pair list.
void link_by_search(DisjointSets& sets, const Grid<float>& g, const int32_t* submesh_of_vertex, size_t submesh_count,
                    double epsilon, int threads) {
    const size_t n = g.items.size(), parts = thread_count(threads, n);
    std::vector<DisjointSets> forests;
    forests.reserve(parts);
    for (size_t t = 0; t < parts; ++t) forests.emplace_back(t == 0 ? 0 : submesh_count);
    const double r2 = epsilon * epsilon;
    run_parallel(parts, [&](size_t t) {
        DisjointSets& own = t == 0 ? sets : forests[t];
        for (size_t k = n * t / parts; k < n * (t + 1) / parts; ++k) {
            const uint32_t i = g.items[k];
            const float* q = &g.sorted_positions[3 * k];
            const double p[3] = {q[0], q[1], q[2]};
            const uint32_t si = uint32_t(submesh_of_vertex[i]);
            visit_near(g, p, epsilon, 0, [&](uint32_t m) {
                const uint32_t j = g.items[m];
                const uint32_t sj = uint32_t(submesh_of_vertex[j]);
                if (j <= i || sj == si || distance2(g, p, m) > r2) return false;
                own.unite(si, sj);
                return false;
            });
        }
    });
    for (size_t t = 1; t < parts; ++t)
        for (uint32_t s = 0; s < submesh_count; ++s) sets.unite(s, forests[t].find(s));
}

// Dense points (crowded cells: coincident vertices, an epsilon as wide as the mesh): cells of
// side epsilon / sqrt(3) hold points all within epsilon of each other, so every cell joins its
// submeshes outright; two cells within reach are measured point against point only while their
// sets differ, up to the first pair within epsilon. Linear memory; linear time when the cells
// join (the cases that make the search above quadratic). Returns false (nothing done) when cells
// that small cannot be numbered exactly.
bool link_by_cells(DisjointSets& sets, const float* positions, size_t vertex_count, const int32_t* submesh_of_vertex,
                   double epsilon) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < vertex_count; ++v)
        for (int d = 0; d < 3; ++d) {
            lo[d] = std::min(lo[d], double(positions[3 * v + d]));
            hi[d] = std::max(hi[d], double(positions[3 * v + d]));
        }
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    const double side = epsilon / std::sqrt(3.0) * (1 - 1e-6);
    const bool exact = side == 0.0;  // epsilon 0: a cell is one exact position
    if (!exact && extent / side > std::ldexp(1.0, 40)) return false;
    struct Keyed {
        double key[3];
        uint32_t vertex;
    };
    std::vector<Keyed> cells(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) {
        cells[v].vertex = uint32_t(v);
        for (int d = 0; d < 3; ++d) {
            const double x = double(positions[3 * v + d]);
            cells[v].key[d] = exact ? x + 0.0 : std::floor((x - lo[d]) / side);
        }
    }
    auto less = [](const Keyed& a, const Keyed& b) {
        return std::lexicographical_compare(a.key, a.key + 3, b.key, b.key + 3);
    };
    std::sort(cells.begin(), cells.end(), less);
    std::vector<uint32_t> start;  // first entry of each cell
    for (size_t k = 0; k < vertex_count; ++k)
        if (k == 0 || less(cells[k - 1], cells[k])) start.push_back(uint32_t(k));
    start.push_back(uint32_t(vertex_count));
    const size_t cell_count = start.size() - 1;
    auto sub = [&](size_t k) { return uint32_t(submesh_of_vertex[cells[k].vertex]); };
    for (size_t c = 0; c < cell_count; ++c)
        for (uint32_t k = start[c] + 1; k < start[c + 1]; ++k) sets.unite(sub(start[c]), sub(k));
    if (exact) return true;
    const double r2 = epsilon * epsilon;
    auto find_cell = [&](const double key[3]) -> size_t {
        Keyed probe{{key[0], key[1], key[2]}, 0};
        size_t a = 0, b = cell_count;
        while (a < b) {
            const size_t mid = (a + b) / 2;
            if (less(cells[start[mid]], probe))
                a = mid + 1;
            else
                b = mid;
        }
        return a < cell_count && !less(probe, cells[start[a]]) ? a : cell_count;
    };
    for (size_t c = 0; c < cell_count; ++c) {
        const double* key = cells[start[c]].key;
        for (int dx = -2; dx <= 2; ++dx)
            for (int dy = -2; dy <= 2; ++dy)
                for (int dz = -2; dz <= 2; ++dz) {
                    // each neighbour once: offsets after (0, 0, 0) in lexicographic order
                    if (dx < 0 || (dx == 0 && (dy < 0 || (dy == 0 && dz <= 0)))) continue;
                    const double other_key[3] = {key[0] + dx, key[1] + dy, key[2] + dz};
                    const size_t o = find_cell(other_key);
                    if (o == cell_count || sets.find(sub(start[c])) == sets.find(sub(start[o]))) continue;
                    bool joined = false;
                    for (uint32_t a = start[c]; a < start[c + 1] && !joined; ++a) {
                        const float* p = positions + 3 * size_t(cells[a].vertex);
                        for (uint32_t b = start[o]; b < start[o + 1]; ++b) {
                            const float* q = positions + 3 * size_t(cells[b].vertex);
                            const double ex = double(p[0]) - q[0], ey = double(p[1]) - q[1], ez = double(p[2]) - q[2];
                            if (ex * ex + ey * ey + ez * ez <= r2) {
                                sets.unite(sub(a), sub(b));
                                joined = true;
                                break;
                            }
                        }
                    }
                }
    }
    return true;
}

}  // namespace

size_t select_linked_across(uint8_t* out_selected, const uint8_t* selected, const float* positions,
                            const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count, double epsilon,
                            int threads) {
    check_submesh_ids(submesh_of_vertex, vertex_count, submesh_count);
    check_radius(epsilon, "epsilon");
    check_finite_positions(positions, vertex_count);
    std::vector<uint8_t> marked = touched_submeshes(selected, submesh_of_vertex, vertex_count, submesh_count);
    // Submeshes linked by close vertices form one region; a region the selection touches is
    // selected whole.
    DisjointSets sets(submesh_count);
    if (vertex_count >= 2) {
        std::vector<uint32_t> all(vertex_count);
        for (size_t v = 0; v < vertex_count; ++v) all[v] = uint32_t(v);
        Grid<float> g;
        build_grid(g, positions, all, epsilon, nullptr);
        std::vector<uint32_t>().swap(all);
        if (g.crowding <= 64.0 || !link_by_cells(sets, positions, vertex_count, submesh_of_vertex, epsilon))
            link_by_search(sets, g, submesh_of_vertex, submesh_count, epsilon, threads);
    }
    std::vector<uint8_t> region_marked(submesh_count, 0);
    for (uint32_t s = 0; s < submesh_count; ++s)
        if (marked[s]) region_marked[sets.find(s)] = 1;
    for (uint32_t s = 0; s < submesh_count; ++s) marked[s] = region_marked[sets.find(s)];
    return expand_submeshes(out_selected, marked, submesh_of_vertex, vertex_count);
}

}  // namespace boxmarch
