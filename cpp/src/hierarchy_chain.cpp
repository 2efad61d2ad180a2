// Rule Chain of the box hierarchy: each box's parent is the lower-numbered box with the nearest
// origin. The finite origins are put once into a k-d tree (kd_tree.h) whose nodes know the lowest
// box number below them: box i descends it nearer side first, skipping nodes that hold no box
// below i and nodes whose bounds lie farther than the nearest lower box found so far. The tree
// follows the origins wherever they are (clusters any distance apart, all boxes at one origin),
// so no box compares itself with every other. Boxes are independent of one another, so they are
// searched in parallel.
#include "internal.h"
#include "kd_tree.h"
#include "spatial_hash.h"

#include <mutex>

namespace boxmarch {

namespace {

glm::dvec3 vec3_at(const double* a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

}  // namespace

// Boxes with a NaN or infinite origin coordinate are at NaN or infinite distance from every box:
// they are nobody's parent and have none.
void chain_parents(int32_t* parent, const double* origins, size_t count, SearchWork* work) {
    std::vector<uint32_t> finite;
    for (size_t i = 0; i < count; ++i)
        if (finite_point(origins + 3 * i)) finite.push_back(uint32_t(i));
    KdTree tree;
    build_kd_tree(tree, origins, std::move(finite));
    std::fill(parent, parent + count, -1);
    // In tree order, so that boxes searched one after the other read the same nodes.
    const size_t n = tree.items.size(), parts = thread_count(0, n);
    std::mutex counted;
    run_parallel(parts, [&](size_t part) {
        SearchWork done;
        for (size_t k = n * part / parts; k < n * (part + 1) / parts; ++k) {
            const uint32_t i = tree.items[k];
            const glm::dvec3 o = vec3_at(origins, i);
            // The distance of the contract, glm::length of the difference; the bound is the same
            // length of the gap to a node's bounds, which no difference inside is shorter than.
            auto distance = [&](uint32_t j) { return glm::length(o - vec3_at(origins, j)); };
            auto bound = [&](const KdTree::Node& node) {
                glm::dvec3 gap;
                gap_to(&o.x, node, &gap.x);
                return glm::length(gap);
            };
            double best = INFINITY;
            int64_t nearest = -1;
            nearest_in_tree(tree, i, distance, bound, best, nearest, done);
            parent[i] = int32_t(nearest);
        }
        const std::lock_guard<std::mutex> lock(counted);
        if (work) work->add(done);
    });
}

}  // namespace boxmarch
