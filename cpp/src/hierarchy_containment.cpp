// Rule Containment of the box hierarchy: each box's parent is the smallest larger box whose
// oriented bounds hold its origin. A box j can only hold points within its bounding sphere, so
// the holders are grouped by the size of that sphere (classes a factor of 2 apart) and each
// class is hashed into a grid with cells as wide as its largest sphere: a point looks up at most
// 27 cells per class, and a few huge boxes sit in a grid of their own instead of in every cell of
// the small ones. A cell lists its boxes smallest first, so a point tests the boxes larger than
// itself in order up to the first that holds it. Every candidate is decided by the exact inside
// test and the smallest holder by a strict order, so the parents do not depend on how the
// candidates are found.
#include "internal.h"
#include "spatial_hash.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <map>

namespace boxmarch {

namespace {

glm::dvec3 vec3_at(const double* a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

double volume(const double* half_extents, size_t i) {
    const glm::dvec3 h = vec3_at(half_extents, i);
    return h.x * h.y * h.z;
}

// The larger of two boxes by volume, ties to the lower index: a strict order, so containment
// parents always point to larger boxes and can form no cycle (a NaN volume is larger than
// nothing and nothing is larger than it).
bool larger(const double* half_extents, size_t a, size_t b) {
    const double va = volume(half_extents, a), vb = volume(half_extents, b);
    return va > vb || (va == vb && a < b);
}

// Bounds of box j as its inside test reads them: half-extents plus 1e-6 of the largest one.
glm::dvec3 inside_bounds(const double* half_extents, size_t j) {
    const glm::dvec3 h = vec3_at(half_extents, j);
    const double slack = 1e-6 * std::max(h.x, std::max(h.y, h.z));
    return h + slack;
}

bool holds(const double* origins, const float* quaternions, const double* half_extents, size_t j, size_t i) {
    const float* q = quaternions + j * 4;
    const glm::dquat to_local = glm::conjugate(glm::dquat(q[3], q[0], q[1], q[2]));
    const glm::dvec3 local = to_local * (vec3_at(origins, i) - vec3_at(origins, j));
    const glm::dvec3 b = inside_bounds(half_extents, j);
    return std::abs(local.x) <= b.x && std::abs(local.y) <= b.y && std::abs(local.z) <= b.z;
}

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Radius around box j's origin outside which its inside test fails for every point, or infinity
// when no useful radius is known (infinite bounds, or a quaternion too far from unit length).
// glm rotates v by a quaternion of squared norm s2 as (1 - s2) v + s2 R v, whose length is at
// least m |v| with m = 1 for s2 >= 1 and |1 - 2 s2| below; the inside test bounds |local| by
// |b|. Margins cover the rounding (below 1e-7 |v| for s2 <= 1e6).
double holding_radius(const float* quaternions, const double* half_extents, size_t j) {
    const glm::dvec3 b = inside_bounds(half_extents, j);
    const float* q = quaternions + j * 4;
    const double s2 = double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3];
    const double m = s2 >= 1.0 ? 1.0 : std::abs(1.0 - 2.0 * s2);
    if (!finite3(b) || !(s2 <= 1e6) || !(m >= 0.25)) return INFINITY;
    return glm::length(b) * (1.0 + 1e-9) / (m - 1e-7);
}

// One size class: the holders with radius in (2^(e-1), 2^e], hashed by their origins.
struct SizeClass {
    std::vector<uint32_t> members;
    double radius = 0.0;  // largest holding radius (grid units)
    double smallest_volume = INFINITY, largest_volume = -INFINITY;
    glm::dvec3 lo{INFINITY}, hi{-INFINITY};  // bounds of the members' origins (grid units)
    Grid<double> grid;
};

struct Holders {
    double scale = 1.0;               // grid units per object unit (grid_scale)
    std::vector<double> scaled;       // origins in grid units
    std::vector<SizeClass> classes;   // hashed holders, smallest spheres first
    std::vector<uint32_t> unbounded;  // holders tested against every point
};

// Sorts every box that can hold anything into a size class or the unbounded list. A box with a
// NaN anywhere in its origin, quaternion or volume, or negative bounds, holds nothing (NaN fails
// every comparison), and a box of finite bounds with an infinite origin coordinate neither holds
// nor is held by one of finite bounds (that local coordinate is infinite or NaN).
Holders sort_holders(const double* origins, const float* quaternions, const double* half_extents, size_t count) {
    Holders h;
    std::vector<double> radius(count, NAN);  // NaN: holds nothing
    double largest = 0.0;
    for (size_t j = 0; j < count; ++j) {
        const glm::dvec3 o = vec3_at(origins, j), b = inside_bounds(half_extents, j);
        const float* q = quaternions + j * 4;
        if (finite3(o)) largest = std::max({largest, std::abs(o.x), std::abs(o.y), std::abs(o.z)});
        if (glm::any(glm::isnan(o)) || std::isnan(q[0]) || std::isnan(q[1]) || std::isnan(q[2]) || std::isnan(q[3]) ||
            std::isnan(volume(half_extents, j)) || !(b.x >= 0.0 && b.y >= 0.0 && b.z >= 0.0))
            continue;
        radius[j] = holding_radius(quaternions, half_extents, j);
        if (std::isfinite(radius[j])) largest = std::max(largest, radius[j]);
    }
    h.scale = grid_scale(largest);
    h.scaled.resize(count * 3);
    for (size_t i = 0; i < count * 3; ++i) h.scaled[i] = origins[i] * h.scale;
    std::map<int, size_t> class_of_exponent;
    for (size_t j = 0; j < count; ++j) {
        if (std::isnan(radius[j])) continue;
        if (!std::isfinite(radius[j])) {
            h.unbounded.push_back(uint32_t(j));
            continue;
        }
        if (!finite3(vec3_at(origins, j))) continue;
        const double scaled_radius = radius[j] * h.scale * (1.0 + 1e-9) + 1e-300;
        int e;
        std::frexp(scaled_radius, &e);
        auto found = class_of_exponent.emplace(e, h.classes.size());
        if (found.second) h.classes.emplace_back();
        SizeClass& c = h.classes[found.first->second];
        c.members.push_back(uint32_t(j));
        c.radius = std::max(c.radius, scaled_radius);
        c.smallest_volume = std::min(c.smallest_volume, volume(half_extents, j));
        c.largest_volume = std::max(c.largest_volume, volume(half_extents, j));
        const glm::dvec3 s = vec3_at(h.scaled.data(), j);
        c.lo = glm::min(c.lo, s);
        c.hi = glm::max(c.hi, s);
    }
    std::sort(h.classes.begin(), h.classes.end(),
              [](const SizeClass& a, const SizeClass& b) { return a.radius < b.radius; });
    // Smallest first: build_grid keeps this order inside each bucket.
    for (SizeClass& c : h.classes) {
        std::sort(c.members.begin(), c.members.end(),
                  [&](uint32_t a, uint32_t b) { return larger(half_extents, b, a); });
        build_grid(c.grid, h.scaled.data(), c.members, c.radius, nullptr);
    }
    return h;
}

}  // namespace

void containment_parents(int32_t* parent, const double* origins, const float* quaternions, const double* half_extents,
                         size_t count) {
    const Holders h = sort_holders(origins, quaternions, half_extents, count);
    const size_t parts = thread_count(0, count);
    run_parallel(parts, [&](size_t part) {
        for (size_t i = count * part / parts; i < count * (part + 1) / parts; ++i) {
            int64_t best = -1;
            for (uint32_t j : h.unbounded)
                if (j != i && larger(half_extents, j, i) && holds(origins, quaternions, half_extents, j, i) &&
                    (best < 0 || larger(half_extents, size_t(best), j)))
                    best = int64_t(j);
            const glm::dvec3 p = vec3_at(h.scaled.data(), i);
            const double v = volume(half_extents, i);
            if (finite3(p) && !std::isnan(v))
                for (const SizeClass& c : h.classes) {
                    // Classes of smaller boxes, or whose spheres all miss p, cannot hold it; a
                    // class of boxes all larger than the holder found cannot hold it closer.
                    if (c.largest_volume < v || (best >= 0 && c.smallest_volume > volume(half_extents, size_t(best))) ||
                        glm::any(glm::lessThan(p, c.lo - c.radius)) || glm::any(glm::greaterThan(p, c.hi + c.radius)))
                        continue;
                    const double at[3] = {p.x, p.y, p.z};
                    uint64_t buckets[27];
                    for (int k = 0, nb = near_buckets(c.grid, at, c.radius, 0, buckets); k < nb; ++k) {
                        // A bucket lists its boxes smallest first: past those not larger than i
                        // (i too, if there), the first that holds i is the bucket's smallest holder.
                        const uint32_t* end = c.grid.items.data() + c.grid.bucket_start[buckets[k] + 1];
                        const uint32_t* j =
                                std::partition_point(c.grid.items.data() + c.grid.bucket_start[buckets[k]], end,
                                                     [&](uint32_t box) { return !larger(half_extents, box, i); });
                        for (; j != end && (best < 0 || larger(half_extents, size_t(best), *j)); ++j)
                            if (holds(origins, quaternions, half_extents, *j, i)) {
                                best = int64_t(*j);
                                break;
                            }
                    }
                }
            parent[i] = int32_t(best);
        }
    });
}

}  // namespace boxmarch
