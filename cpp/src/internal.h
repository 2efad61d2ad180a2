// Shared pieces of the bake that are not part of the public contract.
#pragma once

#include "boxmarch/boxmarch.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

namespace boxmarch {

// parallel.cpp: the only place the core starts threads.
// Threads for a job when the caller asked for `requested` (0 or less: all cores).
size_t hardware_threads(int requested);
// Runs work(part) for part = 0..parts-1, part 0 on the caller's thread, and waits for all. An
// exception thrown by any part (std::bad_alloc included) is rethrown here after every part has
// finished (the first part's, in part order); when no thread can be started the parts run on the
// caller's thread. Never lets an exception reach std::terminate.
void run_parallel(size_t parts, const std::function<void(size_t)>& work);

// hierarchy_containment.cpp, hierarchy_chain.cpp: the geometric rules of box_hierarchy (its
// contract in boxmarch.h), writing parent[count] only; nearest_points (nearest_points.cpp). Each
// adds the work its search did to *work where that is not null (the scaling tests read it).
struct SearchWork;
void containment_parents(int32_t* parent, const double* origins, const float* quaternions, const double* half_extents,
                         size_t count, SearchWork* work = nullptr);
void chain_parents(int32_t* parent, const double* origins, size_t count, SearchWork* work = nullptr);
void nearest_points_counted(int64_t* nearest, const double* points, size_t point_count, const double* candidates,
                            size_t candidate_count, int threads, SearchWork* work);

// One submesh seen through the whole mesh: its vertices (ascending), faces and edges as lists of
// indices into the mesh's arrays. base is the position of its lowest vertex in double: every
// computation works relative to it so far-away submeshes keep their precision.
struct SubmeshView {
    const MeshView* mesh;
    const uint32_t* vertices;
    uint32_t vertex_count;
    const uint32_t* faces;
    uint32_t face_count;
    const uint32_t* edges;
    uint32_t edge_count;
    glm::dvec3 base;

    glm::dvec3 position(uint32_t v) const {
        const float* p = mesh->positions + size_t(v) * 3;
        return glm::dvec3(p[0], p[1], p[2]) - base;
    }
};

// Index of the first i in 0..count-1 with bad(i), or count when there is none. Blocks are
// scanned without early exit (an OR of compares, which vectorises on plain SSE2), so checking valid
// input runs at memory speed; only a block holding a bad value is searched element by element.
template <class Bad>
size_t first_failing(size_t count, Bad&& bad) {
    constexpr size_t kBlock = 1024;
    size_t i = 0;
    for (; i + kBlock <= count; i += kBlock) {
        uint32_t any = 0;
        for (size_t j = i; j < i + kBlock; ++j) any |= uint32_t(bad(j));
        if (any) break;
    }
    for (; i < count; ++i)
        if (bad(i)) return i;
    return count;
}

// Index of the first value outside 0..limit-1, or count when every value is inside.
inline size_t first_out_of_range(const int32_t* values, size_t count, size_t limit) {
    // As unsigned, a negative value is above any limit below 2^31.
    const uint32_t bound = uint32_t(std::min<size_t>(limit, size_t(1) << 31));
    return first_failing(count, [&](size_t i) { return uint32_t(values[i]) >= bound; });
}

// Index of the first NaN or infinite value, or count when all are finite (a float is not finite
// exactly when its exponent bits are all set).
inline size_t first_non_finite(const float* values, size_t count) {
    return first_failing(count, [&](size_t i) {
        uint32_t bits;
        std::memcpy(&bits, values + i, sizeof bits);
        return (bits & 0x7FFFFFFFu) >= 0x7F800000u;
    });
}

// Throws std::invalid_argument naming the first vertex with a NaN or infinite coordinate.
void check_finite_positions(const float* positions, size_t count);

// Throws std::invalid_argument naming the first vertex whose submesh id is outside
// 0..submesh_count-1 (the range every function taking submesh_of_vertex promises to check).
void check_submesh_ids(const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count);

// Counting sort of items by their submesh. Reads submesh_of_item[item_count] (values in
// 0..submesh_count-1); writes offsets[submesh_count + 1] and items[item_count] so the items of
// submesh s are items[offsets[s] .. offsets[s+1]-1], ascending. Throws std::invalid_argument
// (writing nothing) on a value out of range. Internal: dedup's grouping, tested on its own.
void group_by_submesh(uint32_t* offsets, uint32_t* items, const int32_t* submesh_of_item, size_t item_count,
                      size_t submesh_count);

// Counting sort of items by their submesh owner(i) (ids in 0..submesh_count-1; callers check),
// in two halves so callers can skip the second. count_by_owner writes offsets[submesh_count + 1]
// (the items of submesh s take places offsets[s] .. offsets[s+1]-1) and returns true when the
// owners are already ascending: then the grouped order is the items' own order.
template <class Owner>
bool count_by_owner(uint32_t* offsets, size_t item_count, size_t submesh_count, Owner&& owner) {
    std::fill(offsets, offsets + submesh_count + 1, 0u);
    bool sorted = true;
    int32_t previous = 0;
    for (size_t i = 0; i < item_count; ++i) {
        const int32_t sm = owner(i);
        ++offsets[size_t(sm) + 1];
        sorted = sorted && previous <= sm;
        previous = sm;
    }
    for (size_t sm = 0; sm < submesh_count; ++sm) offsets[sm + 1] += offsets[sm];
    return sorted;
}

// Writes items[item_count]: the item indices in grouped order, from count_by_owner's offsets.
template <class Owner>
void scatter_by_owner(uint32_t* items, const uint32_t* offsets, size_t item_count, size_t submesh_count,
                      Owner&& owner) {
    std::vector<uint32_t> cursor(offsets, offsets + submesh_count);
    for (size_t i = 0; i < item_count; ++i) items[cursor[size_t(owner(i))]++] = uint32_t(i);
}

// Relative band inside which two face areas (or edge lengths, or extents) count as equal; the
// lowest index wins such a tie, so float noise cannot pick between opposite faces of a box.
constexpr double kTieBand = 1e-3;

// Which geometry a frame's two directions come from. Indices are positions in the submesh's face
// or edge list, so a decision made on one copy names the same elements on another.
enum class DirectionKind : uint8_t { None, Face, Edge, World };

struct FrameChoice {
    DirectionKind first_kind = DirectionKind::None;
    DirectionKind second_kind = DirectionKind::None;
    uint32_t first = 0;
    uint32_t second = 0;
    // True when every comparison behind the choice clears its threshold by more than the effect
    // of moving each vertex by `displacement`: a copy that close makes the same choice.
    bool stable = false;
};

FrameSource frame_source(const FrameChoice& choice);

// A candidate direction (face or edge): its vector (a face's Newell sum, twice its vector area,
// or an edge's span), whose squared length ranks it, so ranking and the angle test need no square
// root. The slacks, the size and the margin are filled only for the copy cache (displacement > 0):
// how far a copy's vertex displacement could move the size and turn the direction.
struct Candidate {
    glm::dvec3 vector;
    double size2;        // squared length of vector: 4 area^2 for faces, length^2 for edges
    double size;         // face area or edge length (displacement > 0 only)
    double size_slack;   // how much the size may move on a copy within the displacement
    double angle_slack;  // radians the direction may turn on that copy
    bool usable;         // not degenerate (zero area or length)
    bool eligible;       // passes the current selection's test
    double margin;       // how clearly it passes or fails that test (<= 0: a copy may differ)
};

// Buffers choose_frame reuses from one submesh to the next.
struct FrameScratch {
    std::vector<Candidate> faces, edges;
};

// Reads the submesh's faces (and edges when faces cannot orient it); returns the choice the bake's rules make (largest face,
// next face at least angle_epsilon off its plane, fallbacks for flat and face-less submeshes).
// stable is judged for vertex displacements up to `displacement` (object units) when that is
// positive; a choice made with displacement 0 is not judged (stable stays true).
FrameChoice choose_frame(const SubmeshView& s, double cos_epsilon, double displacement, FrameScratch& scratch);

// Builds the orthonormal right-handed frame (columns = local axes in object space) that a choice
// names, from the submesh's own geometry. The same arithmetic serves fresh and cached choices.
// measured: the scratch choose_frame just filled for this submesh and choice (its directions are
// reused), or null (a cached choice: the two directions are measured here).
glm::dmat3 frame_from_choice(const FrameChoice& choice, const SubmeshView& s, const FrameScratch* measured);

// Unit quaternion (x, y, z, w) of a rotation matrix with w >= 0 (and, at w == 0, the first
// nonzero of x, y, z positive), so the same frame always gives the same four numbers.
glm::dvec4 quaternion_from_frame(const glm::dmat3& frame);

// Centroid of a submesh's vertices (relative to its base) and the root-mean-square distance from it.
struct Spread {
    glm::dvec3 centre;
    double rms;
};
Spread spread_of(const SubmeshView& s);

// Similarity-copy cache of frame choices (fingerprint.cpp). Not thread-safe: one per thread.
class CopyCache {
public:
    explicit CopyCache(double tolerance);
    ~CopyCache();
    CopyCache(const CopyCache&) = delete;
    CopyCache& operator=(const CopyCache&) = delete;
    // Bucket key of s: equal for every copy that could match (counts and similarity-invariant
    // distance ratios, coarsely quantised). Lets callers send copies to the same cache and skip
    // the cache for submeshes whose key nobody else has.
    static uint64_t key(const SubmeshView& s, const Spread& spread);
    // Returns true and sets choice when a stored submesh with this key maps onto s by a rotation,
    // uniform scale and translation within tolerance * rms at every vertex, with identical
    // topology. Mirrored copies never match (the map is a proper rotation).
    bool lookup(const SubmeshView& s, const Spread& spread, uint64_t key, FrameChoice& choice) const;
    // Stores s and its (stable) choice for later copies; silently ignores it past the size cap.
    void insert(const SubmeshView& s, const Spread& spread, uint64_t key, const FrameChoice& choice);
    // Largest vertex displacement a matching copy can have, for choose_frame's stability test.
    double displacement(const Spread& spread) const { return tolerance_ * spread.rms; }

private:
    struct Impl;
    Impl* impl_;
    double tolerance_;
};

// encode.cpp: the colour encoding of local offsets f (vector from vertex to origin, box-local).
// Decoding is the blog post's GetFragToOrigin: f = (rgb * 2 - 1) / a, with one alpha per submesh.

// Offsets up to this size are encoded as zero, so 1 / largest stays finite in float32: boxes of
// 1e-30 units still encode exactly; smaller ones have denormal float32 positions and are counted
// as degenerate by the bake.
constexpr double kSmallestEncodableOffset = 1.0 / 3.4028234663852886e38;

// Writes rgba[v * 4 ..] for each listed vertex v from offsets[i] (i-th listed vertex): rgb =
// 0.5 + 0.5 * s * f, a = s, s = 1 / largest |component| (1 when every offset is zero).
// Returns s.
float encode_float(const glm::dvec3* offsets, const uint32_t* vertices, uint32_t count, float* rgba);

// Byte colour (raw bytes, as Unity's Color32 and Blender's color_srgb hold them): among the 32
// largest alphas A/255 that keep a*f inside the representable range, the one whose rounded bytes
// decode with the least worst-case error. Writes rgba bytes; returns the chosen alpha A/255.
float encode_byte(const glm::dvec3* offsets, const uint32_t* vertices, uint32_t count, uint8_t* rgba);

// The decode formula, in double, from stored values.
// (One division per vertex: the three components share 1 / a, as shader compilers make them.)
inline glm::dvec3 decode_float(const float* rgba) {
    return (glm::dvec3(rgba[0], rgba[1], rgba[2]) * 2.0 - 1.0) * (1.0 / double(rgba[3]));
}
inline glm::dvec3 decode_byte(const uint8_t* rgba) {
    return (glm::dvec3(rgba[0], rgba[1], rgba[2]) * (2.0 / 255.0) - 1.0) * (255.0 / double(rgba[3]));
}

// The shaders' bm_rotate_vector: v + 2 cross(q.xyz, cross(q.xyz, v) + q.w v), with q as stored.
inline glm::dvec3 rotate_vector(const glm::dvec3& v, const float* q) {
    const glm::dvec3 u(q[0], q[1], q[2]);
    return v + 2.0 * glm::cross(u, glm::cross(u, v) + double(q[3]) * v);
}

// 32-bit fingerprint of a submesh's exact positions and topology, mixed with seed. words is
// scratch reused from one submesh to the next.
uint32_t fingerprint_submesh(const SubmeshView& s, uint32_t seed, std::vector<uint32_t>& words);

}  // namespace boxmarch
