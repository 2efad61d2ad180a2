// Rule Containment of the box hierarchy: each box's parent is the smallest larger box whose
// oriented bounds hold its origin. The boxes are visited from the smallest to the largest (the
// order `larger` defines); each first claims, among the origins of the boxes visited before it
// (all smaller) that no box has claimed yet, those its bounds hold, then puts its own origin
// among them. The first box to claim an origin is the smallest larger box holding it, which is
// the definition, so every origin is claimed at most once. The unclaimed origins live in a k-d
// tree (kd_tree.h) that counts them per node: a box reads only nodes with unclaimed origins
// whose bounds its oriented box may reach, so nested boxes and boxes at one origin cost about
// what spread boxes do. A node is tested against the box's own axes and the object's (misses);
// a long box (longest edge 4 times the next or more) against its centre line widened by its
// cross-section instead (misses_line: a slab clip, about as tight as the full separating-axis
// test and a third of the arithmetic), so a turned long thin box reads only the nodes its line
// passes through. Cost: a box reads the nodes its bounds meet. A long thin box crossing a region
// of m origins still meets about (m / 8)^(1/3) leaves and about 5 times as many nodes above them,
// so n such boxes cost n^(4/3) (2.52x per doubling; deciding whether any of n points lies on any
// of n lines is Hopcroft's problem, with no known near-linear method), and a flat box crossing
// the region meets about (m / 8)^(2/3) leaves: n^(5/3) (3.17x per doubling; simplex range
// searching in linear space takes about m^(2/3) per query, Chazelle's lower bound). The origins
// are kept in the tree's order beside it, so a leaf's points are read in one run rather than one
// cache miss each. Every claim is decided by the exact inside test.
#include "internal.h"
#include "kd_tree.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

namespace boxmarch {

namespace {

glm::dvec3 vec3_at(const double* a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

double volume(const double* half_extents, size_t i) {
    const glm::dvec3 h = vec3_at(half_extents, i);
    return h.x * h.y * h.z;
}

// Bounds of box j as its inside test reads them: half-extents plus 1e-6 of the largest one.
glm::dvec3 inside_bounds(const double* half_extents, size_t j) {
    const glm::dvec3 h = vec3_at(half_extents, j);
    const double slack = 1e-6 * std::max(h.x, std::max(h.y, h.z));
    return h + slack;
}

// What box j's inside test reads, to decide it for a whole node of origins. rows[a] holds the map
// glm's rotation by j's conjugate quaternion applies to a difference (a linear map whatever the
// quaternion's length): local axis a of d is dot(rows[a], d), rounded. box_hierarchy refuses
// non-finite origins and quaternions and negative or NaN half-extents; bounds may be infinite.
struct Holder {
    glm::dvec3 origin, bounds, rows[3];
    glm::dvec3 reach{INFINITY};  // half-size along each object axis of what the bounds can hold
    // A long box (its longest edge at least 4 times the next) is read as its centre line: the
    // segment t * axis, |t| <= half_length, widened by `widen` along each object axis (see
    // misses_line); other boxes, and maps far from a rotation or infinite bounds, by misses.
    bool long_box = false;
    glm::dvec3 axis{0.0}, inverse_axis{0.0}, widen{0.0};
    double half_length = 0.0;
    double length2 = 0.0;  // the quaternion's squared length

    glm::dquat to_local;

    Holder(const double* origins, const float* quaternions, const double* half_extents, size_t j)
            : origin(vec3_at(origins, j)), bounds(inside_bounds(half_extents, j)) {
        const float* q = quaternions + j * 4;
        to_local = glm::conjugate(glm::dquat(q[3], q[0], q[1], q[2]));
        for (int k = 0; k < 3; ++k) {
            glm::dvec3 axis(0.0);
            axis[k] = 1.0;
            const glm::dvec3 column = to_local * axis;
            for (int a = 0; a < 3; ++a) rows[a][k] = column[a];
        }
        length2 = double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3];
        // The held differences d satisfy |dot(rows[a], d)| <= bounds[a] (within rounding): d lies
        // in the inverse image of the bounds, within |inverse| * bounds per object axis, widened
        // by 1e-6 for the rounding of the rotation and of the inverse; only where the map is far
        // from singular (condition below 1e3: a quaternion of length 1 +- 0.1 or so), so that
        // the rotation's rounding, amplified by the inverse, stays far below that margin. An
        // infinite bound leaves the axes it reaches unbounded (0 * infinity is NaN: not finite).
        const glm::dmat3 to_object = glm::transpose(glm::dmat3(rows[0], rows[1], rows[2]));
        const glm::dmat3 back = glm::inverse(to_object);
        double largest = 0.0, largest_back = 0.0;
        for (int a = 0; a < 3; ++a)
            for (int d = 0; d < 3; ++d)
                largest = std::max(largest, std::abs(to_object[a][d])),
                largest_back = std::max(largest_back, std::abs(back[a][d]));
        for (int d = 0; d < 3 && largest * largest_back < 1e3; ++d) {
            double r = 0.0;
            for (int a = 0; a < 3; ++a) r += std::abs(back[a][d]) * bounds[a];
            if (std::isfinite(r)) reach[d] = r * (1.0 + 1e-6);
        }
        // Every held difference d has |d[k]| <= reach[k], so glm's rotation of it is off by less
        // than e = 1e-9 (1 + 2 length2) |d|_1 on each local axis (the margin misses takes): d
        // lies in the bounds widened by e, that is at t * axis plus sum over the other local axes
        // a of s_a * back[a] (|t| <= bounds[longest] + e, |s_a| <= bounds[a] + e), within the
        // segment widened by sum |back[a]| (bounds[a] + e) per object axis; 1e-9 of the largest
        // of those terms more covers the rounding of the inverse (condition below 1e3), and 1e-9
        // of the half-length that of its sum.
        const double reach_sum = reach.x + reach.y + reach.z;
        if (largest * largest_back < 1e3 && std::isfinite(reach_sum)) {
            const double e = 1e-9 * (1.0 + 2.0 * length2) * reach_sum;
            double edge[3];
            for (int a = 0; a < 3; ++a) edge[a] = bounds[a] * glm::length(back[a]);
            int longest = 0;
            for (int a = 1; a < 3; ++a)
                if (edge[a] > edge[longest]) longest = a;
            const double next = std::max(edge[(longest + 1) % 3], edge[(longest + 2) % 3]);
            if (edge[longest] >= 4.0 * next) {
                long_box = true;
                axis = back[longest];
                half_length = (bounds[longest] + e) * (1.0 + 1e-9);
                double largest_term = half_length * largest_back;
                for (int a = 0; a < 3; ++a)
                    if (a != longest)
                        widen += glm::abs(back[a]) * (bounds[a] + e),
                                largest_term = std::max(largest_term, (bounds[a] + e) * largest_back);
                widen += 1e-9 * largest_term;
                for (int d = 0; d < 3; ++d) inverse_axis[d] = axis[d] != 0.0 ? 1.0 / axis[d] : 0.0;
            }
        }
    }

    // The inside test: the point p (an origin) lies in the box's bounds.
    bool holds(const double* p) const {
        const glm::dvec3 local = to_local * (glm::dvec3(p[0], p[1], p[2]) - origin);
        return std::abs(local.x) <= bounds.x && std::abs(local.y) <= bounds.y && std::abs(local.z) <= bounds.z;
    }

    // For a long box, true when no origin inside the node's bounds can pass the inside test: the
    // held differences in the node, within [lo, hi] - origin (rounding is monotonic), lie on the
    // segment widened (see the constructor) only where the segment's parameter t meets every
    // axis's slab [lo - widen, hi + widen] / axis[d] and |t| <= half_length; each slab is taken
    // 1e-9 of its ends wider for the rounding of the sums and the division. A NaN (an overflowed
    // difference) is never a reason to skip the node.
    bool misses_line(const KdTree::Node& n) const {
        double first = -half_length, last = half_length;
        for (int d = 0; d < 3; ++d) {
            const double lo = n.lo[d] - origin[d] - widen[d], hi = n.hi[d] - origin[d] + widen[d];
            if (inverse_axis[d] == 0.0) {
                if (lo - 1e-9 * std::abs(lo) > 0.0 || hi + 1e-9 * std::abs(hi) < 0.0) return true;
                continue;
            }
            double from = lo * inverse_axis[d], to = hi * inverse_axis[d];
            if (from > to) std::swap(from, to);
            const double slack = 1e-9 * (std::abs(from) + std::abs(to));
            first = std::max(first, from - slack), last = std::min(last, to + slack);
        }
        return first > last;
    }

    // True when no origin inside the node's bounds can pass the inside test: every difference
    // p - origin of such a p rounds into [lo, hi] - origin (rounding is monotonic), which lies
    // within reach on the object axes only if it overlaps it, and whose image under the rows lies
    // within centre +- extent on each local axis; the margin covers the rounding of glm's
    // rotation and of this bound by a factor of about 1e6. A NaN (an overflowed difference)
    // fails every comparison: the node is read.
    bool misses(const KdTree::Node& n) const {
        glm::dvec3 middle, half;
        double size = 0.0;
        for (int d = 0; d < 3; ++d) {
            const double lo = n.lo[d] - origin[d], hi = n.hi[d] - origin[d];
            if (lo * (1.0 - 1e-9) > reach[d] || -hi * (1.0 - 1e-9) > reach[d]) return true;
            middle[d] = 0.5 * lo + 0.5 * hi;
            half[d] = 0.5 * hi - 0.5 * lo;
            size += std::abs(middle[d]) + half[d];
        }
        const double margin = 1e-9 * (1.0 + 2.0 * length2) * size;
        for (int a = 0; a < 3; ++a) {
            const double centre = glm::dot(rows[a], middle), extent = glm::dot(glm::abs(rows[a]), half);
            if (std::abs(centre) - extent - margin > bounds[a]) return true;
        }
        return false;
    }
};

// The origins not yet claimed: a k-d tree over them with a count per node.
struct Unclaimed {
    KdTree tree;
    std::vector<uint32_t> live;      // per node
    std::vector<uint8_t> is_live;    // per position in tree.items
    std::vector<uint32_t> position;  // of each box in tree.items
    std::vector<double> points;      // the origins in tree.items' order: a leaf's are read in one run
    SearchWork work;

    void add(uint32_t i) {
        const uint32_t at = position[i];
        is_live[at] = 1;
        for (uint32_t node = 0;;) {
            ++live[node];
            const KdTree::Node& n = tree.nodes[node];
            if (!n.children) break;
            node = at < tree.nodes[n.children].end ? n.children : n.children + 1;
        }
    }

    // Claims for box j every unclaimed origin its bounds hold below `node`; returns how many.
    uint32_t claim(uint32_t node, const Holder& h, int32_t* parent, uint32_t j) {
        if (!live[node]) return 0;
        ++work.nodes;
        const KdTree::Node& n = tree.nodes[node];
        if (h.long_box ? h.misses_line(n) : h.misses(n)) return 0;
        uint32_t claimed = 0;
        if (n.children) {
            claimed = claim(n.children, h, parent, j) + claim(n.children + 1, h, parent, j);
        } else {
            for (uint32_t k = n.begin; k < n.end; ++k) {
                if (!is_live[k]) continue;
                ++work.candidates;
                if (h.holds(&points[3 * size_t(k)])) parent[tree.items[k]] = int32_t(j), is_live[k] = 0, ++claimed;
            }
        }
        live[node] -= claimed;
        return claimed;
    }
};

}  // namespace

void containment_parents(int32_t* parent, const double* origins, const float* quaternions, const double* half_extents,
                         size_t count, SearchWork* work) {
    std::fill(parent, parent + count, -1);
    // A box with a NaN volume (a zero and an infinite half-extent) is neither larger nor smaller
    // than any other: it holds nothing and nothing holds it.
    std::vector<uint32_t> order;
    std::vector<double> volumes(count);
    for (size_t i = 0; i < count; ++i) {
        volumes[i] = volume(half_extents, i);
        if (!std::isnan(volumes[i])) order.push_back(uint32_t(i));
    }
    Unclaimed u;
    build_kd_tree(u.tree, origins, order);
    // Smallest first: the larger of two boxes is the one of larger volume, ties to the lower
    // index (a strict order, so parents always point to larger boxes and form no cycle).
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return volumes[a] < volumes[b] || (volumes[a] == volumes[b] && a > b); });
    u.live.assign(u.tree.nodes.size(), 0);
    u.is_live.assign(u.tree.items.size(), 0);
    u.position.assign(count, 0);
    u.points.resize(3 * u.tree.items.size());
    for (size_t k = 0; k < u.tree.items.size(); ++k) {
        u.position[u.tree.items[k]] = uint32_t(k);
        std::copy_n(origins + 3 * size_t(u.tree.items[k]), 3, &u.points[3 * k]);
    }
    for (uint32_t j : order) {
        const Holder h(origins, quaternions, half_extents, j);
        if (!u.tree.nodes.empty()) u.claim(0, h, parent, j);
        u.add(j);
    }
    if (work) work->add(u.work);
}

}  // namespace boxmarch
