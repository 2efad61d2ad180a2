// Fixed-radius neighbour pairs on a hash grid, shared by the submesh tools (not public).
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace boxmarch {

using PointPair = std::pair<uint32_t, uint32_t>;

// Every unordered pair i < j of points with |p_i - p_j| <= radius, computed in double from the
// stored T values. group_of_point (may be null): points with a negative group are left out, and
// only pairs of different groups are reported. Pairs come in no particular order. Expects a
// finite radius >= 0 and finite positions (callers check).
template <class T>
std::vector<PointPair> close_pairs(const T* positions, size_t count, double radius,
                                   const int32_t* group_of_point, int threads);

// Sorts found (by i, then j) and writes the first `capacity` pairs into pairs[capacity * 2], the
// output contract of find_close_pairs; returns how many pairs there are in all.
size_t write_sorted_pairs(uint32_t* pairs, size_t capacity, std::vector<PointPair>& found);

// Threads to use for `work_items` items when the caller asked for `requested` (0: all cores).
size_t thread_count(int requested, size_t work_items);

// Throws std::invalid_argument naming `what` when value is negative, NaN or infinite.
void check_radius(double value, const char* what);

}  // namespace boxmarch

namespace boxmarch {

// components.cpp: connected components of a graph given as links between nodes 0..node_count-1.
// Writes label[node_count] numbered 0.. in order of each component's lowest node; returns the
// number of components.
size_t label_components(std::vector<uint32_t>& label, size_t node_count, const std::vector<PointPair>& links);

}  // namespace boxmarch
