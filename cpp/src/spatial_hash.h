// Fixed-radius neighbour search on a hash grid, shared by the submesh tools (not public).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace boxmarch {

using PointPair = std::pair<uint32_t, uint32_t>;

// Points hashed into cells at least `radius` wide (as wide as their density allows), sorted by
// bucket so that a bucket is one contiguous run of `items` and `sorted_positions`. With `key`
// set, a point's bucket mixes key[point] in, so points of different keys (submeshes) rarely
// share a bucket and a search restricted to one key skips the others.
template <class T>
struct Grid {
    double origin[3] = {0, 0, 0};
    double cell = 1.0;
    uint64_t mask = 0;
    double crowding = 0.0;  // mean number of points sharing a point's bucket
    const int32_t* key = nullptr;
    std::vector<uint32_t> bucket_start;  // mask + 2 entries
    std::vector<uint32_t> bucket_end;    // live end of each bucket (callers that remove items)
    std::vector<uint32_t> items;         // point indices, sorted by bucket
    std::vector<T> sorted_positions;     // xyz of items[k] at 3k
};

// Builds g over the points named by included (a bucket lists its points in that order). Expects finite positions and a finite
// radius >= 0. key (may be null) as above.
template <class T>
void build_grid(Grid<T>& g, const T* positions, const std::vector<uint32_t>& included, double radius,
                const int32_t* key);

// A power of 2 bringing magnitudes up to `largest` (finite) to at most 2^300, for grids over
// double positions: build_grid multiplies cell sizes together, which must stay finite. Scaling by
// a power of 2 is exact (but for results below 2^-1022, off by at most 2^-1074).
inline double grid_scale(double largest) {
    int exponent;
    std::frexp(largest, &exponent);
    return exponent > 300 ? std::ldexp(1.0, 300 - exponent) : 1.0;
}

inline uint64_t cell_hash(int64_t x, int64_t y, int64_t z, int32_t key) {
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull + uint64_t(y) * 0xC2B2AE3D27D4EB4Full +
                 uint64_t(z) * 0x165667B19E3779F9ull + uint64_t(uint32_t(key)) * 0x94D049BB133111EBull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 32);
}

// Writes the buckets a point p (in double) can have partners within `radius` in (its own cell,
// and neighbours on sides p is within `radius` of), restricted to key `key` when the grid has
// keys; returns how many (at most 27, no repeats).
template <class T>
int near_buckets(const Grid<T>& g, const double p[3], double radius, int32_t key, uint64_t buckets[27]) {
    const double near = radius / g.cell + 1e-6;
    int64_t cell[3];
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        const double u = (p[d] - g.origin[d]) / g.cell;
        const double f = std::floor(u);
        cell[d] = int64_t(f);
        lo[d] = (u - f < near) ? -1 : 0;
        hi[d] = (u - f > 1.0 - near) ? 1 : 0;
    }
    int nb = 0;
    const int32_t k = g.key ? key : 0;
    for (int dx = lo[0]; dx <= hi[0]; ++dx)
        for (int dy = lo[1]; dy <= hi[1]; ++dy)
            for (int dz = lo[2]; dz <= hi[2]; ++dz) {
                const uint64_t b = cell_hash(cell[0] + dx, cell[1] + dy, cell[2] + dz, k) & g.mask;
                if (std::find(buckets, buckets + nb, b) == buckets + nb) buckets[nb++] = b;
            }
    return nb;
}

template <class T>
inline uint32_t bucket_last(const Grid<T>& g, uint64_t b) {
    return g.bucket_end.empty() ? g.bucket_start[b + 1] : g.bucket_end[b];
}

// Calls visit(slot) for every item slot in near_buckets (slots bucket_start[b] .. bucket_end[b]
// when bucket_end is set, else .. bucket_start[b + 1]). visit returns true to stop. Callers
// decide pairs by the true distance.
template <class T, class Visit>
void visit_near(const Grid<T>& g, const double p[3], double radius, int32_t key, Visit&& visit) {
    uint64_t buckets[27];
    const int nb = near_buckets(g, p, radius, key, buckets);
    for (int q = 0; q < nb; ++q)
        for (uint32_t m = g.bucket_start[buckets[q]], end = bucket_last(g, buckets[q]); m < end; ++m)
            if (visit(m)) return;
}

template <class T>
inline double distance2(const Grid<T>& g, const double p[3], uint32_t slot) {
    const T* q = &g.sorted_positions[3 * size_t(slot)];
    const double dx = p[0] - double(q[0]), dy = p[1] - double(q[1]), dz = p[2] - double(q[2]);
    return dx * dx + dy * dy + dz * dz;
}

// Every unordered pair i < j of points with |p_i - p_j| <= radius, computed in double from the
// stored T values. group_of_point (may be null): points with a negative group are left out, and
// only pairs of different groups are reported. Pairs come in no particular order. Expects a
// finite radius >= 0 and finite positions (callers check). The pairs are materialised: only for
// callers that return them (find_close_pairs); the tools use the searches below.
template <class T>
std::vector<PointPair> close_pairs(const T* positions, size_t count, double radius, const int32_t* group_of_point,
                                   int threads);

// Writes has_partner[i] = 1 for every point i (group_of_point[i] >= 0) with another point of the
// same group within radius, else 0. Stops at the first partner: linear memory and, on coincident
// points, linear time.
void mark_points_with_partner(uint8_t* has_partner, const float* positions, size_t count, double radius,
                              const int32_t* group_of_point, int threads);

// Sorts found (by i, then j) and writes the first `capacity` pairs into pairs[capacity * 2], the
// output contract of find_close_pairs; returns how many pairs there are in all.
size_t write_sorted_pairs(uint32_t* pairs, size_t capacity, std::vector<PointPair>& found);

// Threads to use for `work_items` items when the caller asked for `requested` (0: all cores).
size_t thread_count(int requested, size_t work_items);

// Throws std::invalid_argument naming `what` when value is negative, NaN or infinite.
void check_radius(double value, const char* what);

// Union-find over 0..n-1 (path halving; the lower root becomes the parent, so a set's root is
// its lowest member).
struct DisjointSets {
    std::vector<uint32_t> parent;
    explicit DisjointSets(size_t n) : parent(n) {
        for (size_t i = 0; i < n; ++i) parent[i] = uint32_t(i);
    }
    uint32_t find(uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    }
    bool unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return false;
        if (a < b) std::swap(a, b);
        parent[a] = b;
        return true;
    }
};

}  // namespace boxmarch

namespace boxmarch {

// components.cpp: connected components of a graph given as links between nodes 0..node_count-1.
// Writes label[node_count] numbered 0.. in order of each component's lowest node; returns the
// number of components.
size_t label_components(std::vector<uint32_t>& label, size_t node_count, const std::vector<PointPair>& links);

}  // namespace boxmarch
