// A k-d tree over finite points (median splits on the widest axis, tight bounds per node), shared
// by the nearest-point searches (nearest_points.cpp, the CHAIN hierarchy rule in
// hierarchy_chain.cpp) and the CONTAINMENT rule's range searches (hierarchy_containment.cpp); not
// public. It adapts to where the points are, not to their bounding box: clusters far apart,
// queries far from every point and many points at one place cost no more than spread ones.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace boxmarch {

// Work a search did, counted for the scaling tests (tests/cpp/test_hierarchy.cpp).
struct SearchWork {
    uint64_t nodes = 0;       // tree nodes reached
    uint64_t candidates = 0;  // points measured
    void add(const SearchWork& w) { nodes += w.nodes, candidates += w.candidates; }
};

struct KdTree {
    static constexpr uint32_t kLeafSize = 8;
    struct Node {
        double lo[3], hi[3];  // bounds of the node's points
        uint32_t begin, end;  // its points: items[begin, end)
        uint32_t lowest;      // the lowest point number among them
        uint32_t children;    // the first of its two children (the second follows it); 0: a leaf
    };
    std::vector<Node> nodes;
    std::vector<uint32_t> items;  // point numbers; a leaf's ascending
};

inline bool finite_point(const double* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

namespace kd_detail {

inline void build_node(KdTree& t, const double* points, uint32_t node, uint32_t begin, uint32_t end) {
    KdTree::Node n;
    n.begin = begin, n.end = end, n.children = 0;
    n.lowest = std::numeric_limits<uint32_t>::max();
    for (int d = 0; d < 3; ++d) n.lo[d] = INFINITY, n.hi[d] = -INFINITY;
    for (uint32_t k = begin; k < end; ++k) {
        const double* p = points + 3 * size_t(t.items[k]);
        for (int d = 0; d < 3; ++d) n.lo[d] = std::min(n.lo[d], p[d]), n.hi[d] = std::max(n.hi[d], p[d]);
        n.lowest = std::min(n.lowest, t.items[k]);
    }
    if (end - begin <= KdTree::kLeafSize) {
        std::sort(t.items.begin() + begin, t.items.begin() + end);
        t.nodes[node] = n;
        return;
    }
    // Points at one place are split too (by number), so that every node holds at most half of
    // its parent's points and the depth stays log2(count).
    int axis = 0;
    for (int d = 1; d < 3; ++d)
        if (n.hi[d] - n.lo[d] > n.hi[axis] - n.lo[axis]) axis = d;
    const uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(t.items.begin() + begin, t.items.begin() + middle, t.items.begin() + end,
                     [&](uint32_t a, uint32_t b) {
                         const double pa = points[3 * size_t(a) + axis], pb = points[3 * size_t(b) + axis];
                         return pa < pb || (pa == pb && a < b);
                     });
    n.children = uint32_t(t.nodes.size());
    t.nodes[node] = n;
    t.nodes.resize(t.nodes.size() + 2);
    build_node(t, points, n.children, begin, middle);
    build_node(t, points, n.children + 1, middle, end);
}

}  // namespace kd_detail

// Builds t over the points numbered in `included` (each with finite coordinates in points[3 * i]).
inline void build_kd_tree(KdTree& t, const double* points, std::vector<uint32_t> included) {
    t.items = std::move(included);
    t.nodes.assign(1, KdTree::Node{});
    if (t.items.empty()) {
        t.nodes.clear();
        return;
    }
    t.nodes.reserve(4 * (t.items.size() / KdTree::kLeafSize + 1));
    kd_detail::build_node(t, points, 0, 0, uint32_t(t.items.size()));
}

// The per-axis gap from p to the bounds [lo, hi] as the difference p - q of the nearest q inside
// would be rounded: for every q in the bounds, |fl(p - q)| >= |gap| axis by axis (rounding is
// monotonic), so a norm that grows with each |component| bounds the node's distances from below
// exactly, ties included.
inline void gap_to(const double p[3], const KdTree::Node& n, double gap[3]) {
    for (int d = 0; d < 3; ++d) gap[d] = p[d] < n.lo[d] ? p[d] - n.lo[d] : p[d] > n.hi[d] ? p[d] - n.hi[d] : 0.0;
}

// The point numbered below `limit` nearest to a query, ties to the lowest number: bound(node)
// never exceeds distance(j) for any point j of the node, distance(j) is the query's distance to
// point j (NaN or infinite: never taken). Starts from best/best_point (infinity, -1: none) and
// updates them. Visits the nearer child first and skips a node whose bound exceeds the best
// distance, or equals it with no lower number inside.
template <class Distance, class Bound>
void nearest_in_tree(const KdTree& t, uint32_t limit, Distance&& distance, Bound&& bound, double& best,
                     int64_t& best_point, SearchWork& work) {
    if (t.nodes.empty()) return;
    auto skip = [&](const KdTree::Node& n, double b) {
        return n.lowest >= limit || !(b <= best) || b == INFINITY || (b == best && int64_t(n.lowest) >= best_point);
    };
    auto visit = [&](auto&& self, uint32_t index) -> void {
        const KdTree::Node& n = t.nodes[index];
        ++work.nodes;
        if (!n.children) {
            for (uint32_t k = n.begin; k < n.end && t.items[k] < limit; ++k) {
                const uint32_t j = t.items[k];
                ++work.candidates;
                const double d = distance(j);
                if (d < best || (d == best && best_point >= 0 && int64_t(j) < best_point)) best = d, best_point = j;
            }
            return;
        }
        uint32_t first = n.children, second = n.children + 1;
        double b_first = bound(t.nodes[first]), b_second = bound(t.nodes[second]);
        if (b_second < b_first || (b_second == b_first && t.nodes[second].lowest < t.nodes[first].lowest))
            std::swap(first, second), std::swap(b_first, b_second);
        if (!skip(t.nodes[first], b_first)) self(self, first);
        if (!skip(t.nodes[second], b_second)) self(self, second);
    };
    if (!skip(t.nodes[0], bound(t.nodes[0]))) visit(visit, 0);
}

}  // namespace boxmarch
