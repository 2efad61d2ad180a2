// Connected components of a graph given as a list of links (breadth-first over a CSR adjacency).
#include "spatial_hash.h"

namespace boxmarch {

size_t label_components(std::vector<uint32_t>& label, size_t node_count, const std::vector<PointPair>& links) {
    std::vector<uint32_t> start(node_count + 1, 0), next(2 * links.size());
    for (const PointPair& l : links) {
        ++start[l.first + 1];
        ++start[l.second + 1];
    }
    for (size_t n = 0; n < node_count; ++n) start[n + 1] += start[n];
    std::vector<uint32_t> cursor(start.begin(), start.end() - 1);
    for (const PointPair& l : links) {
        next[cursor[l.first]++] = l.second;
        next[cursor[l.second]++] = l.first;
    }
    const uint32_t unset = UINT32_MAX;
    label.assign(node_count, unset);
    std::vector<uint32_t> queue;
    size_t count = 0;
    for (size_t root = 0; root < node_count; ++root) {
        if (label[root] != unset) continue;
        label[root] = uint32_t(count);
        queue.assign(1, uint32_t(root));
        for (size_t head = 0; head < queue.size(); ++head)
            for (uint32_t k = start[queue[head]]; k < start[queue[head] + 1]; ++k)
                if (label[next[k]] == unset) {
                    label[next[k]] = uint32_t(count);
                    queue.push_back(next[k]);
                }
        ++count;
    }
    return count;
}

}  // namespace boxmarch
