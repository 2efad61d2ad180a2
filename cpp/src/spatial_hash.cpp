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

namespace boxmarch {

size_t thread_count(int requested, size_t work_items) {
    const size_t threads = hardware_threads(requested);
    return std::max<size_t>(1, std::min<size_t>({threads, 64, work_items / 4096}));
}

void check_radius(double value, const char* what) {
    if (!std::isfinite(value) || value < 0.0)
        throw std::invalid_argument(std::string(what) + " must be a finite number >= 0, got " + std::to_string(value));
}

template <class T>
void build_grid(Grid<T>& g, const T* p, const std::vector<uint32_t>& included, double radius, const int32_t* key) {
    g.key = key;
    g.bucket_end.clear();
    const size_t n = included.size();
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i : included)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], double(p[3 * size_t(i) + k]));
            hi[k] = std::max(hi[k], double(p[3 * size_t(i) + k]));
        }
    if (n == 0)
        for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0.0;
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
            bucket_of[k] = uint32_t(cell_hash(x, y, z, key ? key[included[k]] : 0) & g.mask);
            ++g.bucket_start[bucket_of[k] + 1];
        }
        double crowding = 0.0;
        for (size_t b2 = 1; b2 <= table; ++b2) crowding += double(g.bucket_start[b2]) * double(g.bucket_start[b2]);
        crowding /= std::max<size_t>(1, n);
        g.crowding = crowding;
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

template void build_grid<float>(Grid<float>&, const float*, const std::vector<uint32_t>&, double, const int32_t*);
template void build_grid<double>(Grid<double>&, const double*, const std::vector<uint32_t>&, double, const int32_t*);

namespace {

std::vector<uint32_t> included_points(size_t count, const int32_t* group_of_point) {
    std::vector<uint32_t> included;
    included.reserve(count);
    for (size_t i = 0; i < count; ++i)
        if (!group_of_point || group_of_point[i] >= 0) included.push_back(uint32_t(i));
    return included;
}

template <class T>
void query_range(const Grid<T>& g, size_t first, size_t last, double radius, const int32_t* group,
                 std::vector<PointPair>& out) {
    const double r2 = radius * radius;
    for (size_t k = first; k < last; ++k) {
        const uint32_t i = g.items[k];
        const T* t = &g.sorted_positions[3 * k];
        const double pi[3] = {double(t[0]), double(t[1]), double(t[2])};
        const int32_t gi = group ? group[i] : 0;
        visit_near(g, pi, radius, 0, [&](uint32_t m) {
            const uint32_t j = g.items[m];
            if (j <= i || (group && group[j] == gi)) return false;
            if (distance2(g, pi, m) <= r2) out.emplace_back(i, j);
            return false;
        });
    }
}

}  // namespace

template <class T>
std::vector<PointPair> close_pairs(const T* positions, size_t count, double radius, const int32_t* group_of_point,
                                   int threads) {
    const std::vector<uint32_t> included = included_points(count, group_of_point);
    if (included.size() < 2) return {};
    Grid<T> g;
    build_grid(g, positions, included, radius, nullptr);
    const size_t n = included.size(), parts = thread_count(threads, n);
    std::vector<std::vector<PointPair>> found(parts);
    run_parallel(parts, [&](size_t t) {
        query_range(g, n * t / parts, n * (t + 1) / parts, radius, group_of_point, found[t]);
    });
    size_t total = 0;
    for (const auto& f : found) total += f.size();
    found[0].reserve(total);
    for (size_t t = 1; t < parts; ++t) {
        found[0].insert(found[0].end(), found[t].begin(), found[t].end());
        std::vector<PointPair>().swap(found[t]);
    }
    return std::move(found[0]);
}

template std::vector<PointPair> close_pairs<float>(const float*, size_t, double, const int32_t*, int);
template std::vector<PointPair> close_pairs<double>(const double*, size_t, double, const int32_t*, int);

void mark_points_with_partner(uint8_t* has_partner, const float* positions, size_t count, double radius,
                              const int32_t* group_of_point, int threads) {
    std::fill(has_partner, has_partner + count, uint8_t(0));
    const std::vector<uint32_t> included = included_points(count, group_of_point);
    if (included.size() < 2) return;
    Grid<float> g;
    build_grid(g, positions, included, radius, group_of_point);
    const double r2 = radius * radius;
    const size_t n = included.size(), parts = thread_count(threads, n);
    run_parallel(parts, [&](size_t t) {
        for (size_t k = n * t / parts; k < n * (t + 1) / parts; ++k) {
            const uint32_t i = g.items[k];
            const float* q = &g.sorted_positions[3 * k];
            const double pi[3] = {q[0], q[1], q[2]};
            const int32_t gi = group_of_point ? group_of_point[i] : 0;
            visit_near(g, pi, radius, gi, [&](uint32_t m) {
                const uint32_t j = g.items[m];
                if (j == i || (group_of_point && group_of_point[j] != gi) || distance2(g, pi, m) > r2) return false;
                has_partner[i] = 1;
                return true;
            });
        }
    });
}

size_t write_sorted_pairs(uint32_t* pairs, size_t capacity, std::vector<PointPair>& found) {
    std::sort(found.begin(), found.end());
    for (size_t k = 0; k < std::min(capacity, found.size()); ++k) {
        pairs[2 * k] = found[k].first;
        pairs[2 * k + 1] = found[k].second;
    }
    return found.size();
}

size_t find_close_pairs(uint32_t* pairs, size_t capacity, const float* positions, size_t count, double radius,
                        const int32_t* group_of_point, int threads) {
    check_radius(radius, "radius");
    check_finite_positions(positions, count);
    std::vector<PointPair> found = close_pairs(positions, count, radius, group_of_point, threads);
    return write_sorted_pairs(pairs, capacity, found);
}

}  // namespace boxmarch
