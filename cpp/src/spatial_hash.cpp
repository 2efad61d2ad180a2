// Fixed-radius neighbour pairs on a hash grid. Cells are at least `radius` wide, so a partner of
// a point lies in its own cell or in a neighbour on a side the point is within `radius` of; the
// pair itself is always decided by the true distance, so cell borders and the origin play no
// role. Cells are made as wide as the point density allows (few points per cell), which makes
// almost every point look only at its own cell: one contiguous run of the sorted points.
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "spatial_hash.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

namespace boxmarch {

size_t thread_count(int requested, size_t work_items) {
    size_t threads = requested > 0 ? size_t(requested) : std::max(1u, std::thread::hardware_concurrency());
    return std::max<size_t>(1, std::min<size_t>({threads, 64, work_items / 4096}));
}

void check_radius(double value, const char* what) {
    if (!std::isfinite(value) || value < 0.0)
        throw std::invalid_argument(std::string(what) + " must be a finite number >= 0, got " + std::to_string(value));
}

namespace {

// Positions are kept in their own type (float positions compare exactly in double anyway).
template <class T>
struct Grid {
    double origin[3];
    double cell;
    uint64_t mask;
    std::vector<uint32_t> bucket_start;  // mask + 2 entries
    std::vector<uint32_t> items;         // included points, sorted by bucket
    std::vector<T> sorted_positions;     // xyz of items[k] at 3k
};

inline uint64_t cell_hash(int64_t x, int64_t y, int64_t z) {
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull + uint64_t(y) * 0xC2B2AE3D27D4EB4Full +
                 uint64_t(z) * 0x165667B19E3779F9ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 32);
}

template <class T>
void build(Grid<T>& g, const T* p, const std::vector<uint32_t>& included, double radius) {
    const size_t n = included.size();
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i : included)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], double(p[3 * size_t(i) + k]));
            hi[k] = std::max(hi[k], double(p[3 * size_t(i) + k]));
        }
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    for (int k = 0; k < 3; ++k) g.origin[k] = lo[k];
    // At most 2^26 cells per axis keeps the fraction inside a cell exact to ~1e-8 of a cell.
    const double min_cell = std::max({radius * (1.0 + 1e-6), extent * std::ldexp(1.0, -26), 1e-30});

    // First guess: cells for about two points each if they filled the bounding box evenly
    // (flat or thin point sets count their thin axes as one cell).
    const double target = std::max(1.0, double(n) / 2.0);
    double a = min_cell, b = std::max(min_cell, extent * 2.0 + 1e-30);
    auto cells_at = [&](double c) {
        return (std::floor((hi[0] - lo[0]) / c) + 1) * (std::floor((hi[1] - lo[1]) / c) + 1) *
               (std::floor((hi[2] - lo[2]) / c) + 1);
    };
    for (int it = 0; it < 60 && b > a * (1 + 1e-3); ++it) {
        const double mid = std::sqrt(a * b);
        (cells_at(mid) > target ? a : b) = mid;
    }
    g.cell = b;

    size_t table = 16;
    while (table < 2 * n) table <<= 1;
    g.mask = table - 1;
    std::vector<uint32_t> bucket_of(n);
    g.bucket_start.assign(table + 1, 0);
    // Clustered points (a dense part inside a wide box) crowd some cells: halve the cell size
    // until the mean number of points sharing a point's bucket is small.
    for (int attempt = 0;; ++attempt) {
        std::fill(g.bucket_start.begin(), g.bucket_start.end(), 0);
        for (size_t k = 0; k < n; ++k) {
            const T* q = p + 3 * size_t(included[k]);
            const int64_t x = int64_t(std::floor((double(q[0]) - lo[0]) / g.cell));
            const int64_t y = int64_t(std::floor((double(q[1]) - lo[1]) / g.cell));
            const int64_t z = int64_t(std::floor((double(q[2]) - lo[2]) / g.cell));
            bucket_of[k] = uint32_t(cell_hash(x, y, z) & g.mask);
            ++g.bucket_start[bucket_of[k] + 1];
        }
        double crowding = 0.0;
        for (size_t b2 = 1; b2 <= table; ++b2) crowding += double(g.bucket_start[b2]) * double(g.bucket_start[b2]);
        crowding /= std::max<size_t>(1, n);
        if (crowding <= 24.0 || g.cell <= min_cell || attempt >= 40) break;
        g.cell = std::max(min_cell, g.cell * 0.5);
    }
    for (size_t b2 = 0; b2 < table; ++b2) g.bucket_start[b2 + 1] += g.bucket_start[b2];
    g.items.resize(n);
    g.sorted_positions.resize(3 * n);
    std::vector<uint32_t> cursor(g.bucket_start.begin(), g.bucket_start.end() - 1);
    for (size_t k = 0; k < n; ++k) {
        const uint32_t slot = cursor[bucket_of[k]]++;
        g.items[slot] = included[k];
        for (int d = 0; d < 3; ++d) g.sorted_positions[3 * size_t(slot) + d] = p[3 * size_t(included[k]) + d];
    }
}

template <class T>
void query_range(const Grid<T>& g, size_t first, size_t last, double radius, const int32_t* group,
                 std::vector<PointPair>& out) {
    const double r2 = radius * radius;
    // Points within this fraction of a cell of a side look into the neighbour there; the slack
    // covers rounding of the cell coordinate.
    const double near = radius / g.cell + 1e-6;
    uint64_t buckets[27];
    for (size_t k = first; k < last; ++k) {
        const uint32_t i = g.items[k];
        const T* t = &g.sorted_positions[3 * k];
        const double pi[3] = {double(t[0]), double(t[1]), double(t[2])};
        int64_t cell[3];
        int lo[3], hi[3];
        for (int d = 0; d < 3; ++d) {
            const double u = (pi[d] - g.origin[d]) / g.cell;
            const double f = std::floor(u);
            cell[d] = int64_t(f);
            lo[d] = (u - f < near) ? -1 : 0;
            hi[d] = (u - f > 1.0 - near) ? 1 : 0;
        }
        int nb = 0;
        for (int dx = lo[0]; dx <= hi[0]; ++dx)
            for (int dy = lo[1]; dy <= hi[1]; ++dy)
                for (int dz = lo[2]; dz <= hi[2]; ++dz) {
                    const uint64_t b = cell_hash(cell[0] + dx, cell[1] + dy, cell[2] + dz) & g.mask;
                    if (std::find(buckets, buckets + nb, b) == buckets + nb) buckets[nb++] = b;
                }
        const int32_t gi = group ? group[i] : 0;
        for (int q = 0; q < nb; ++q) {
            for (uint32_t m = g.bucket_start[buckets[q]], end = g.bucket_start[buckets[q] + 1]; m < end; ++m) {
                const uint32_t j = g.items[m];
                if (j <= i || (group && group[j] == gi)) continue;
                const T* pj = &g.sorted_positions[3 * size_t(m)];
                const double dx = pi[0] - pj[0], dy = pi[1] - pj[1], dz = pi[2] - pj[2];
                if (dx * dx + dy * dy + dz * dz <= r2) out.emplace_back(i, j);
            }
        }
    }
}

}  // namespace

template <class T>
std::vector<PointPair> close_pairs(const T* positions, size_t count, double radius,
                                   const int32_t* group_of_point, int threads) {
    std::vector<uint32_t> included;
    included.reserve(count);
    for (size_t i = 0; i < count; ++i)
        if (!group_of_point || group_of_point[i] >= 0) included.push_back(uint32_t(i));
    if (included.size() < 2) return {};
    Grid<T> g;
    build(g, positions, included, radius);
    const size_t n = included.size(), parts = thread_count(threads, n);
    std::vector<std::vector<PointPair>> found(parts);
    std::vector<std::thread> pool;
    for (size_t t = 1; t < parts; ++t)
        pool.emplace_back(query_range<T>, std::cref(g), n * t / parts, n * (t + 1) / parts, radius, group_of_point,
                          std::ref(found[t]));
    query_range(g, 0, n / parts, radius, group_of_point, found[0]);
    for (std::thread& th : pool) th.join();
    for (size_t t = 1; t < parts; ++t) found[0].insert(found[0].end(), found[t].begin(), found[t].end());
    return std::move(found[0]);
}

template std::vector<PointPair> close_pairs<float>(const float*, size_t, double, const int32_t*, int);
template std::vector<PointPair> close_pairs<double>(const double*, size_t, double, const int32_t*, int);

size_t write_sorted_pairs(uint32_t* pairs, size_t capacity, std::vector<PointPair>& found) {
    std::sort(found.begin(), found.end());
    for (size_t k = 0; k < std::min(capacity, found.size()); ++k) {
        pairs[2 * k] = found[k].first;
        pairs[2 * k + 1] = found[k].second;
    }
    return found.size();
}

size_t find_close_pairs(uint32_t* pairs, size_t capacity, const float* positions, size_t count,
                        double radius, const int32_t* group_of_point, int threads) {
    check_radius(radius, "radius");
    check_finite_positions(positions, count);
    std::vector<PointPair> found = close_pairs(positions, count, radius, group_of_point, threads);
    return write_sorted_pairs(pairs, capacity, found);
}

}  // namespace boxmarch
