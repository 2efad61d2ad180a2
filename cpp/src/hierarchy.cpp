// Box hierarchy: each box's parent (given, by containment, or along a chain) and its depth.
#include "internal.h"

#include <glm/gtc/quaternion.hpp>

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

glm::dvec3 vec3_at(const double* a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

// The larger of two boxes by volume, ties to the lower index: a strict order, so containment
// parents always point to larger boxes and can form no cycle.
bool larger(const double* half_extents, size_t a, size_t b) {
    const glm::dvec3 ha = vec3_at(half_extents, a), hb = vec3_at(half_extents, b);
    const double va = ha.x * ha.y * ha.z, vb = hb.x * hb.y * hb.z;
    return va > vb || (va == vb && a < b);
}

void containment_parents(int32_t* parent, const double* origins, const float* quaternions, const double* half_extents,
                         size_t count) {
    for (size_t i = 0; i < count; ++i) {
        parent[i] = -1;
        const glm::dvec3 p = vec3_at(origins, i);
        for (size_t j = 0; j < count; ++j) {
            if (j == i || !larger(half_extents, j, i)) continue;
            const float* q = quaternions + j * 4;
            const glm::dquat to_local = glm::conjugate(glm::dquat(q[3], q[0], q[1], q[2]));
            const glm::dvec3 local = to_local * (p - vec3_at(origins, j));
            const glm::dvec3 h = vec3_at(half_extents, j);
            const double slack = 1e-6 * std::max(h.x, std::max(h.y, h.z));
            const bool inside = std::abs(local.x) <= h.x + slack && std::abs(local.y) <= h.y + slack &&
                                std::abs(local.z) <= h.z + slack;
            if (inside && (parent[i] < 0 || larger(half_extents, size_t(parent[i]), j))) parent[i] = int32_t(j);
        }
    }
}

void chain_parents(int32_t* parent, const double* origins, size_t count) {
    for (size_t i = 0; i < count; ++i) {
        parent[i] = -1;
        double nearest = std::numeric_limits<double>::infinity();
        for (size_t j = 0; j < i; ++j) {
            const double d = glm::length(vec3_at(origins, i) - vec3_at(origins, j));
            if (d < nearest) {
                nearest = d;
                parent[i] = int32_t(j);
            }
        }
    }
}

}  // namespace

int32_t box_hierarchy(int32_t* parent, int32_t* depth, const double* origins, const float* quaternions,
                      const double* half_extents, size_t box_count, HierarchyRule rule, const int32_t* given_parent) {
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
