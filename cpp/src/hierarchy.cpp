// Box hierarchy: each box's parent (given, by containment, or along a chain) and its depth. The
// geometric rules live in hierarchy_containment.cpp and hierarchy_chain.cpp.
#include "internal.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

std::string number_text(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

}  // namespace

int32_t box_hierarchy(int32_t* parent, int32_t* depth, const double* origins, const float* quaternions,
                      const double* half_extents, size_t box_count, HierarchyRule rule, const int32_t* given_parent) {
    // What the bake never makes, and what would make the geometric searches compare every pair.
    for (size_t i = 0; i < 3 * box_count; ++i) {
        if (!(half_extents[i] >= 0.0))
            throw std::invalid_argument("box " + std::to_string(i / 3) + " has half-extent " +
                                        number_text(half_extents[i]) + ": half-extents must be 0 or more");
        if (!std::isfinite(origins[i]))
            throw std::invalid_argument("box " + std::to_string(i / 3) + " has origin coordinate " +
                                        number_text(origins[i]) + ": origins must be finite");
    }
    for (size_t i = 0; i < 4 * box_count; ++i)
        if (!std::isfinite(quaternions[i]))
            throw std::invalid_argument("box " + std::to_string(i / 4) + " has quaternion component " +
                                        number_text(quaternions[i]) + ": quaternions must be finite");
    std::vector<int32_t> parents(box_count);
    if (rule == HierarchyRule::Given) {
        if (!given_parent && box_count) throw std::invalid_argument("rule Given needs the given parents");
        for (size_t i = 0; i < box_count; ++i) {
            const int32_t p = given_parent[i];
            if (p < -1 || (p >= 0 && size_t(p) >= box_count))
                throw std::invalid_argument("box " + std::to_string(i) + " names parent " + std::to_string(p) +
                                            ", outside -1.." + std::to_string(int64_t(box_count) - 1));
            if (p >= 0 && size_t(p) == i)
                throw std::invalid_argument("box " + std::to_string(i) + " is its own parent");
            parents[i] = p;
        }
    } else if (rule == HierarchyRule::Containment) {
        containment_parents(parents.data(), origins, quaternions, half_extents, box_count);
    } else if (rule == HierarchyRule::Chain) {
        chain_parents(parents.data(), origins, box_count);
    } else {
        throw std::invalid_argument("unknown hierarchy rule " + std::to_string(int(rule)));
    }
    // Depths by walking up to a known depth; a walk longer than box_count steps is a cycle.
    std::vector<int32_t> depths(box_count, -1);
    std::vector<size_t> path;
    int32_t deepest = 0;
    for (size_t i = 0; i < box_count; ++i) {
        path.clear();
        size_t at = i;
        while (depths[at] < 0 && parents[at] >= 0) {
            path.push_back(at);
            if (path.size() > box_count)
                throw std::invalid_argument("the parents of box " + std::to_string(i) + " form a cycle");
            at = size_t(parents[at]);
        }
        if (depths[at] < 0) depths[at] = 0;
        int32_t d = depths[at];
        for (auto it = path.rbegin(); it != path.rend(); ++it) depths[*it] = ++d;
        deepest = std::max(deepest, depths[i]);
    }
    std::copy(parents.begin(), parents.end(), parent);
    std::copy(depths.begin(), depths.end(), depth);
    return deepest;
}

}  // namespace boxmarch
