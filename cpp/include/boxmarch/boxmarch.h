// boxmarch: bake box-local frames into mesh vertex data for raymarching inside rasterized boxes.
// Copyright (C) 2026 the boxmarch developers. SPDX-License-Identifier: GPL-3.0-or-later
//
// The one public header of the native core. Every function works on flat arrays that the caller
// owns; counts are element counts, not bytes. Functions throw std::invalid_argument with a
// readable message when their input is malformed (out-of-range indices, non-finite positions,
// mismatched counts) and write nothing in that case. Inputs must not change during a call (the
// checks read them once, before the work): the Python bindings pass private copies, so another
// thread writing the caller's arrays cannot turn a checked index into one out of range.
#pragma once

#include <cstddef>
#include <cstdint>

namespace boxmarch {

// A polygon mesh: positions per vertex, edges as vertex pairs, faces as runs of
// corners (face f owns corners face_starts[f] .. face_starts[f] + face_sizes[f] - 1), each corner
// naming its vertex.
struct MeshView {
    const float* positions = nullptr;  // vertex_count * 3
    size_t vertex_count = 0;
    const int32_t* edges = nullptr;  // edge_count * 2
    size_t edge_count = 0;
    const int32_t* face_starts = nullptr;  // face_count
    const int32_t* face_sizes = nullptr;   // face_count
    size_t face_count = 0;
    const int32_t* corner_verts = nullptr;  // corner_count
    size_t corner_count = 0;
};

// Reads the whole mesh. Throws std::invalid_argument naming the first problem: an index out of
// range, a face with fewer than 3 corners or running past corner_count, a NaN or infinite
// coordinate. Returns normally when the mesh is safe for every other function here.
void validate_mesh(const MeshView& mesh);

// ---------------------------------------------------------------------------------------------
// submesh.cpp: connected components

// Reads edges and face corners; writes submesh_of_vertex[vertex_count] with ids 0..n-1 numbered
// in order of each submesh's lowest vertex index (so the result does not depend on edge order).
// Returns n, the number of submeshes. Expects a validated mesh.
size_t find_submeshes(int32_t* submesh_of_vertex, const MeshView& mesh);

// Recovers face boundaries from corner data alone (for hosts that store corners and corner
// edges but no face sizes, where reading sizes per face is slow). Reads corner_verts[corner_count], corner_edges (the edge
// from each corner to the next corner of its face) and edges[edge_count * 2]. A corner starts a
// new face when its predecessor's edge does not join the two, or when it repeats the current
// face's first vertex (a valid face never repeats a vertex). Writes the start of every face found
// into face_starts (room for corner_count / 3 + 1 entries) and returns how many it wrote; exact
// for valid meshes, so callers compare the count with the real face count. Throws
// std::invalid_argument on an edge or vertex index out of range.
size_t face_starts_from_corner_edges(int32_t* face_starts, const int32_t* corner_verts, const int32_t* corner_edges,
                                     size_t corner_count, const int32_t* edges, size_t edge_count, size_t vertex_count);

// ---------------------------------------------------------------------------------------------
// frame.cpp: the 24 axis-aligned turns

// Fixed list of the 24 proper signed permutation matrices (det = +1), index 0 the identity.
// Writes the 3x3 matrix of turn `index` column-major into matrix[9]: column i is the new local
// axis i expressed in the derived frame. Returns false for an index outside 0..23.
bool axis_turn_matrix(double* matrix, int index);

// ---------------------------------------------------------------------------------------------
// bake.cpp: the whole bake

enum class OriginMode : int { Bounds = 0, Mean = 1 };
enum class ColorEncoding : int { Float = 0, Byte = 1 };

// How the frame of a submesh was derived. Anything but Faces counts as degenerate.
enum class FrameSource : uint8_t {
    Faces = 0,     // two face normals (the normal case)
    FaceEdge = 1,  // one face normal and the longest edge not parallel to it (flat submesh)
    Edges = 2,     // the two longest non-parallel edges (no face with area)
    OneAxis = 3,   // one face normal or edge, and the world axis least aligned with it
    Identity = 4,  // no direction at all (single vertex, coincident vertices)
};

enum class SubmeshStatus : uint8_t {
    Baked = 0,
    Unchanged = 1,    // fingerprint equals the previous bake's: outputs left as they were
    NotSelected = 2,  // bake_mask excluded it: outputs left as they were
};

// The range of BakeOptions::angle_epsilon (radians), the one statement of it: the Python API, the
// bake operator's property limits and the command line read these. Below about 1e-8, cos(epsilon)
// rounds to 1 in double and float noise would decide which face gives the second axis; the
// minimum keeps two decades from there. Both bounds are float32 values, so the operator's
// float32 property holds them exactly.
constexpr double kAngleEpsilonMin = double(1e-6f);
constexpr double kAngleEpsilonMax = double(1.5707963f);  // just below pi/2

struct BakeOptions {
    double angle_epsilon = 0.1;  // radians, kAngleEpsilonMin..kAngleEpsilonMax: axis 2 needs
                                 // |dot(n, axis1)| < cos(angle_epsilon)
    OriginMode origin = OriginMode::Bounds;
    bool sort_axes_by_extent = false;  // local x longest, z shortest, before the turn
    int axis_turn = 0;                 // 0..23, see axis_turn_matrix
    ColorEncoding encoding = ColorEncoding::Float;
    bool use_cache = true;  // reuse frame decisions between similar copies
    int threads = 0;        // 0: hardware concurrency
};

struct BakeReport {
    size_t submesh_count = 0;
    size_t baked = 0;
    size_t cache_hits = 0;
    size_t unchanged = 0;
    size_t not_selected = 0;
    size_t degenerate = 0;
    // Worst decode error over baked submeshes, decoding the stored values in double with
    // f = (rgb * 2 - 1) / a: absolute (object units) and relative to the submesh's largest
    // local half-extent (submeshes with zero extent count as absolute).
    double max_error = 0.0;
    double max_relative_error = 0.0;
};

// What the bake writes. Per vertex, length vertex_count: fingerprints, and the colour of offset_float
// (Float encoding) or offset_byte (Byte encoding; the other may be null). Per submesh, length
// submesh_count (the caller sizes them after find_submeshes, or passes vertex_count, which is
// always enough): the rest.
struct BakeOutput {
    uint32_t* fingerprints = nullptr;  // vertex_count
    float* offset_float = nullptr;     // vertex_count * 4 (Float encoding)
    uint8_t* offset_byte = nullptr;    // vertex_count * 4 (Byte encoding)
    float* quaternions = nullptr;      // x, y, z, w per submesh; unit, w >= 0
    double* origins = nullptr;         // object-space origin, 3 per submesh (may be null)
    double* half_extents = nullptr;    // local half-extents, 3 per submesh (may be null)
    float* scales = nullptr;           // alpha s per submesh (may be null)
    uint8_t* sources = nullptr;        // FrameSource per submesh (may be null)
    uint8_t* statuses = nullptr;       // SubmeshStatus per submesh (may be null)
};

// Bakes every submesh of a validated mesh.
// Reads: mesh; submesh_of_vertex from find_submeshes with its count; bake_mask[vertex_count]
// (may be null: bake everything; else a submesh is baked when any of its vertices is nonzero);
// previous_fingerprints[vertex_count] (may be null: no incremental skip).
// Writes into out: fingerprints (never 0 for a selected submesh; a submesh excluded by
// bake_mask keeps its previous fingerprint, or 0 without one); for baked submeshes only, the
// colour of each vertex (offset_float or offset_byte, by the encoding); and every submesh's
// entry of the per-submesh arrays (for a submesh not baked, zeros and source Identity). Returns
// the report. Throws std::invalid_argument, writing nothing, on invalid options (angle_epsilon
// outside kAngleEpsilonMin..kAngleEpsilonMax or NaN, axis_turn outside 0..23), a missing output
// array, or a numbering with an id out of range or a submesh without vertices. Every frame is
// orthonormal to double rounding, so max_error measures the decode of the stored values against
// the origin the bake defines (MEAN: the vertex mean, whatever the frame).
BakeReport bake(const MeshView& mesh, const int32_t* submesh_of_vertex, size_t submesh_count, const uint8_t* bake_mask,
                const uint32_t* previous_fingerprints, const BakeOptions& options, const BakeOutput& out);

// Writes, for every corner whose submesh has write_submesh[s] != 0 (null: all corners), the pair
// (q.x, q.y) when half == 0 or (q.z, q.w) when half == 1 of its submesh's quaternion into
// corner_uv[corner_count * 2]; other corners are left untouched. Reads corner_verts (values in
// 0..vertex_count-1), submesh_of_vertex[vertex_count] (values in 0..submesh_count-1) and
// quaternions[submesh_count * 4]. Throws std::invalid_argument on an index out of range.
void expand_corner_quaternions(float* corner_uv, int half, const int32_t* corner_verts, size_t corner_count,
                               const int32_t* submesh_of_vertex, size_t vertex_count, const float* quaternions,
                               size_t submesh_count, const uint8_t* write_submesh);

// Fingerprint seed of the options that change the bake's output. Equal options give equal seeds.
uint32_t options_seed(const BakeOptions& options);

// ---------------------------------------------------------------------------------------------
// box_params.cpp: per-box parameters (what an artist paints per submesh) and the per-box random

// Reduces per-element values (faces, corners or vertices) to one value per submesh. Reads
// values[element_count * components] and submesh_of_element[element_count] (ids in
// 0..submesh_count-1). Each submesh takes the value tuple most of its elements hold (compared
// exactly; ties: the tuple whose first element has the lowest index); a submesh without
// elements gets zeros. Writes out_values[submesh_count * components] and
// disagrees[submesh_count] (1 where the submesh's elements hold more than one tuple; may be
// null). Returns the number of disagreeing submeshes. Throws std::invalid_argument (nothing
// written) on components outside 1..4, a NaN or infinite value or an id out of range.
size_t reduce_per_submesh(float* out_values, uint8_t* disagrees, const float* values, size_t element_count,
                          size_t components, const int32_t* submesh_of_element, size_t submesh_count);

// Per-box random value in [0, 1), a multiple of 2^-24 (exact in float32), from the box's bake
// fingerprint and a seed: unchanged box (same geometry, same bake options) and seed, same
// value; any change of either draws a new one. Writes out[count] from fingerprints[count].
void box_random(float* out, const uint32_t* fingerprints, size_t count, uint32_t seed);

// ---------------------------------------------------------------------------------------------
// hierarchy.cpp: which box is each box's parent, and its depth

enum class HierarchyRule : int {
    Given = 0,        // parents as the caller names them (e.g. a painted attribute)
    Containment = 1,  // the smallest larger box whose oriented bounds hold this box's origin
    Chain = 2,        // the box with the nearest origin among lower-numbered boxes (box 0: root)
};

// Reads box_count boxes: origins[3] (object space), quaternions[4] (x, y, z, w; box-local to
// object) and half_extents[3] per box. Rule Given reads given_parent[box_count] (-1: root);
// the other rules ignore it (may be null). Containment: box j holds box i when i's origin lies
// within j's half-extents (plus 1e-6 of j's largest half-extent) in j's frame and j is larger
// (volume, ties: lower index), the parent is the smallest such j. Chain: the parent of box i > 0
// is the j < i nearest to it (ties: lowest j; a distance that overflows to infinity is never
// taken). Neither rule compares every pair. Containment visits the boxes from the
// smallest up, each claiming the unclaimed origins of smaller boxes its bounds hold from a k-d
// tree of the origins (nodes tested against the box's own axes and the object axes, a long box's
// against its centre line; claimed origins dropped), so random, nested and clustered boxes and
// shared origins stay near O(box_count log box_count). The bound is what the boxes' bounds meet:
// n long thin boxes crossing one region of n origins each meet about (n / 8)^(1/3) leaves,
// O(n^(4/3)) in all (points on lines: Hopcroft's problem, with no known near-linear method), and
// n flat boxes crossing it about (n / 8)^(2/3) leaves each, O(n^(5/3)) (linear-space simplex
// range searching: about n^(2/3) per query at best); no arrangement costs more than O(n^2)
// (measured: bench/bench_hostile.py --containment, docs/BENCHMARKS.md; work per box on 20,000
// and 40,000 boxes, tests/cpp/test_hierarchy.cpp); a box with an infinite half-extent holds
// every origin. Chain descends a k-d tree of the
// origins, nearer side first, skipping nodes without a lower box or farther than the nearest
// found: about O(box_count log box_count) for every arrangement tested (clusters any distance
// apart, one origin, curves). Chain runs on all cores, Containment on one; the parents are those
// of the pairwise definitions exactly, ties included, for any thread count.
// Writes parent[box_count] (-1 for a root) and depth[box_count] (0 for a root, parent's + 1
// otherwise). Returns the largest depth. Throws std::invalid_argument (nothing written) on a
// given parent out of -1..box_count-1, a box its own parent or a cycle, or (any rule) a NaN or
// infinite origin coordinate or quaternion component or a negative or NaN half-extent, naming
// the box.
int32_t box_hierarchy(int32_t* parent, int32_t* depth, const double* origins, const float* quaternions,
                      const double* half_extents, size_t box_count, HierarchyRule rule, const int32_t* given_parent);

// ---------------------------------------------------------------------------------------------
// nearest_points.cpp: the nearest of a set of points to each of others

// Reads points[point_count * 3] and candidates[candidate_count * 3] and writes nearest[point_count]:
// for each point the candidate row at the smallest squared distance dx*dx + dy*dy + dz*dz
// (summed in that order in double; ties: the lowest row), so the rows NumPy's argmin over those
// sums picks. Where the largest finite coordinate's magnitude reaches 2^300, every coordinate is
// first scaled by the power of 2 that brings it below 2^300 (exact but below 2^-1022), so no
// square overflows where NumPy's would. A candidate with a NaN or infinite coordinate is never
// taken; a point with one, or without such a candidate, gets -1. Does not compare every pair: the
// finite candidates go into a k-d tree each point descends, nearer side first, up to its
// nearest: about O((point_count + candidate_count) log candidate_count) wherever the points lie
// (near the candidates, far from a compact set of them, clusters any distance apart). threads: 0
// for all cores; the rows do not depend on it.
void nearest_points(int64_t* nearest, const double* points, size_t point_count, const double* candidates,
                    size_t candidate_count, int threads);

// ---------------------------------------------------------------------------------------------
// raymarch.cpp: the CPU reference raymarcher (mirrors shaders/glsl/*.glsl line for line)
//
// Units are box-local: a point p is measured from the submesh's origin along its baked axes, and
// the SDF presets are sized by the box's half-extents h (a 1 x 0.6 x 0.2 box has h = 0.5, 0.3,
// 0.1), so no number has to be typed for the common shapes.

enum class SdfPreset : int {
    Box = 0,         // the box itself: sd_box(p, h)
    Sphere = 1,      // largest sphere inside the box: radius min(h)
    RoundedBox = 2,  // the box with edges rounded by min(h) / 4
    Capsule = 3,     // along local x, radius min(h.y, h.z)
    Cylinder = 4,    // along local z, radius min(h.x, h.y), half-height h.z
    Torus = 5,       // around local z, tube radius min(h.z, min(h.x, h.y) / 2), filling x and y
    Link = 6,        // chain link: ring in the xy plane stretched along x, thickness along z
};
constexpr int kSdfPresetCount = 7;

struct MarchOptions {
    SdfPreset sdf = SdfPreset::Box;
    int max_steps = 64;
    float epsilon = 1e-3f;      // hit when the distance falls below this (box-local units)
    float relaxation = 1.0f;    // each step advances relaxation * distance (below 1: safer)
    float max_distance = 1e6f;  // longest march from the ray's start (box-local units)
    int threads = 0;            // 0: hardware concurrency
};

// Distance from box-local point p[3] to preset `sdf` of a box with half-extents h[3].
float sdf_distance(SdfPreset sdf, const float* p, const float* h);

// The shaders' conservative occluders (box_params.glsl bm_occluder_centre/half): box k (0 <= k <
// kMaxOccluders) inscribed in preset `sdf` drawn in a box of half-extents h[3], clipped to that box.
// Writes its box-local centre[3] and half_extent[3] (all zero: no box at k). Throws
// std::invalid_argument on an unknown preset or k out of range.
constexpr int kMaxOccluders = 4;
void occluder_box(SdfPreset sdf, const float* h, int k, float* centre, float* half_extent);

// Sphere-traces ray_count box-local rays, each inside its own box.
// Reads origins, directions (need not be unit; normalised here) and half_extents, each
// ray_count * 3. A ray marches from where it enters its box (its origin when inside) until it
// leaves the box or travels options.max_distance; a ray that misses the box takes 0 steps.
// Writes hit[ray_count] (1 = distance fell below epsilon), positions[ray_count * 3] (last
// sample point, box-local), normals[ray_count * 3] (unit SDF gradient by forward differences at
// distance max(h) / 10000 from the hit, as the shaders' bm_normal; zero on a miss) and
// steps[ray_count] (SDF evaluations of the march).
// Any output pointer may be null. Throws std::invalid_argument (nothing written) on a ray whose
// direction is (0, 0, 0), max_steps < 0, epsilon <= 0, relaxation outside (0, 2] or
// max_distance <= 0.
void raymarch(const float* origins, const float* directions, const float* half_extents, size_t ray_count,
              const MarchOptions& options, uint8_t* hit, float* positions, float* normals, int32_t* steps);

// What render_boxes draws with and writes; matrices are 4x4 column-major (GLM / OpenGL order).
struct RenderView {
    const float* object_to_clip = nullptr;  // projection * view * object matrix
    const float* object_to_view = nullptr;  // view * object matrix (lighting, eye position)
    uint32_t width = 0, height = 0;
    float base_color[3] = {0.8f, 0.8f, 0.8f};
};

struct RenderImages {
    float* rgba = nullptr;     // height * width * 4, row 0 at the TOP; background left untouched
    float* depth = nullptr;    // height * width window depth (0 near, 1 far); caller fills with 1
    float* normals = nullptr;  // height * width * 3 object-space normals (may be null)
    int32_t* steps = nullptr;  // height * width SDF evaluations, summed over boxes (may be null)
};

// What a GPU would spend on a frame of render_boxes, counted per fragment: a fragment is one
// box's front face at one pixel centre inside the box's silhouette (a back face discards before
// marching unless the eye is inside the box, where it stands in for the front face).
struct RenderCost {
    uint64_t fragments = 0;           // fragments rasterised
    uint64_t marched_fragments = 0;   // fragments that marched (not killed by early depth, not returned
                                      // before the march behind the occluders' depth)
    uint64_t occluded_fragments = 0;  // fragments that returned before the march: their box entry lay
                                      // behind the occluders' depth (RenderPlan::occluders)
    uint64_t lod_fragments = 0;       // of those, drawn by one tap (bm_one_tap) instead of a march
    uint64_t sdf_evaluations = 0;     // map() calls: march steps plus the normal taps of a hit
    uint64_t hidden_fragments = 0;    // marched fragments that are not what the pixel shows at the end
    uint64_t hidden_evaluations = 0;  // their map() calls
    uint64_t covered_pixels = 0;      // pixels inside at least one box's silhouette
};

// How render_boxes takes a hit's normal (RenderPlan::normal).
enum class NormalRule {
    Forward,      // raymarch.glsl bm_normal, what every shader does: three forward differences at
                  // bm_normal_tap from the hit's own distance (the march's last map()): 3 map() calls
    Tetrahedral,  // four tetrahedral taps at max(epsilon, 1e-3 x the largest half-extent): 4 calls
    Central,      // central differences at bm_normal_tap (error second order in the tap): 6 calls;
                  // the accuracy reference of bench/bench_gpu_cost.py
};
constexpr int kNormalRuleCount = 3;

// How render_boxes orders, tests and limits its fragments (the GPU-side techniques of
// docs/BENCHMARKS.md "GPU cost"); the defaults draw as the preview does without them.
struct RenderPlan {
    const uint32_t* order = nullptr;  // box_count indices, the draw order (each box once); null: 0, 1, ...
    bool early_depth = false;         // test the rasterised depth before marching (a declared
                                      // depth_greater/SV_DepthGreaterEqual keeps the hardware doing it)
    float quality = 1.0f;             // the quality knob, 0 < quality <= 1 (raymarch.glsl bm_quality)
    bool occluders = false;           // a depth-only pre-pass of each box's conservative occluders
                                      // (box_params.glsl bm_occluder_*): a fragment whose box entry lies
                                      // behind their nearest depth returns before its march, and no
                                      // march goes past that depth
    NormalRule normal = NormalRule::Forward;
    RenderCost* cost = nullptr;  // counts written here when not null
};

// Renders boxes the way the viewport preview does, one sample at each pixel centre: each box
// (object-space origin[3], quaternion x,y,z,w [4] mapping local to object, half-extents[3]) is
// rasterised as its own box, every covered pixel raymarches the preset in box-local space, and
// the nearest hit wins by depth against the values already in images.depth. A hit's depth is
// never nearer than the rasterised face's (clamped, as the shaders' declared depth_greater
// requires), but for a pixel whose ray starts inside its box (the march from the eye, whose face
// is the far side: the shaders draw those boxes apart, declaring no depth), whose hit writes its
// own depth (at least 0). Boxes are drawn in plan.order; plan.early_depth skips the march of a
// fragment whose rasterised depth fails the depth test (not of one marching from the eye);
// plan.occluders first finds, per pixel, the nearest depth
// of the boxes inscribed in the shapes (bm_occluder_centre/half for the preset; none for a box
// whose drawn box holds the eye) and returns before marching from a fragment whose rasterised
// entry lies behind it, and ends every march at it (every fragment still runs); plan.quality below
// 1 takes secant steps within a share of a pixel of the surface (the hit distance stays
// options.epsilon), caps a box's steps by its size on screen and draws boxes under a few pixels
// with one map() tap (bm_quality); plan.normal picks the normal's differences. Hits are shaded with the
// preview's Lambert + hemisphere light in view space. Reads box_count boxes; writes the covered
// pixels of images and, if plan.cost is set, the counts. Throws std::invalid_argument on bad options (see raymarch), a quality outside (0, 1], an
// unknown normal rule or an order that is not a permutation of the boxes.
void render_boxes(const float* origins, const float* quaternions, const float* half_extents, size_t box_count,
                  const RenderView& view, const MarchOptions& options, const RenderImages& images,
                  const RenderPlan& plan = RenderPlan());

// =============================================================================================
// Submesh tools (select linked, select across, dedup, merge per submesh, pack UVs by Z).
// Positions are compared in double from the stored float32 values; "within r" means a true
// Euclidean distance <= r, whatever the positions (no grid quantisation decides a pair). Every
// tool taking submesh_of_vertex checks its ids lie in 0..submesh_count-1 and throws
// std::invalid_argument (writing nothing) naming the first that does not.

// ---------------------------------------------------------------------------------------------
// spatial_hash.cpp: fixed-radius neighbour pairs

// Reads positions[count * 3]; group_of_point[count] may be null, else only pairs whose points
// lie in different groups count. threads 0: hardware concurrency. Finds every unordered pair
// i < j with |p_i - p_j| <= radius (radius >= 0, finite) with a hash grid whose cells are at
// least radius wide (exact: cells only decide where to look). Writes the first `capacity`
// pairs found, as (i, j), into pairs[capacity * 2] (null when capacity is 0), ordered by i then
// j; returns the total count, so a caller with too little room calls again with more.
// Throws std::invalid_argument on a negative, NaN or infinite radius or a non-finite position.
size_t find_close_pairs(uint32_t* pairs, size_t capacity, const float* positions, size_t count, double radius,
                        const int32_t* group_of_point, int threads);

// kdtree_pairs.cpp: the same contract as find_close_pairs, answered by nanoflann radius searches
// (one per point). Kept as the reference the benchmark and tests compare the hash with.
size_t find_close_pairs_kdtree(uint32_t* pairs, size_t capacity, const float* positions, size_t count, double radius,
                               const int32_t* group_of_point);

// ---------------------------------------------------------------------------------------------
// select_linked.cpp: selection flood fills over whole submeshes

// Reads submesh_of_vertex[vertex_count] (ids 0..submesh_count-1, from find_submeshes) and
// selected[vertex_count]; writes out_selected[vertex_count] = 1 for every vertex of a submesh
// holding a selected vertex, else 0 (may alias selected). Returns the number of such submeshes.
size_t select_linked_submeshes(uint8_t* out_selected, const uint8_t* selected, const int32_t* submesh_of_vertex,
                               size_t vertex_count, size_t submesh_count);

// Flood fill through edges and through vertices of other submeshes within epsilon (true
// Euclidean distance <= epsilon) of a reached vertex. Reads positions[vertex_count * 3],
// submesh_of_vertex (from find_submeshes), selected[vertex_count]; writes out_selected as above
// (may alias selected). Returns the number of submeshes selected. Throws std::invalid_argument
// on a negative, NaN or infinite epsilon or a non-finite position.
size_t select_linked_across(uint8_t* out_selected, const uint8_t* selected, const float* positions,
                            const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count, double epsilon,
                            int threads);

// ---------------------------------------------------------------------------------------------
// dedup.cpp: duplicate submeshes

// A submesh B duplicates A when both have the same vertex count and every vertex of B lies
// within tolerance of a distinct vertex of A (a perfect matching; order and index do not
// matter). Submeshes are visited by id (lowest vertex first); a candidate submesh (candidate
// != null and candidate[s] != 0, or every submesh when null) that duplicates an earlier kept
// candidate is marked, so the lowest-index copy of each set stays. Reads positions,
// submesh_of_vertex (from find_submeshes); writes duplicate_of[submesh_count] (-1: kept or not a
// candidate; else the kept submesh it duplicates). Returns the number of duplicates. Candidates
// come from a hash of submesh centroids, never from comparing all pairs. Throws
// std::invalid_argument on a negative, NaN or infinite tolerance or a non-finite position.
size_t find_duplicate_submeshes(int32_t* duplicate_of, const float* positions, const int32_t* submesh_of_vertex,
                                size_t vertex_count, size_t submesh_count, const uint8_t* candidate, double tolerance,
                                int threads);

// ---------------------------------------------------------------------------------------------
// merge.cpp: merge by distance inside each submesh

// Plans a merge by distance inside each chosen submesh (chosen[s] != 0) for a merge that works
// on a vertex selection (a host's own merge by distance): only vertices with a partner of their
// own submesh within `distance` can merge, so only they need selecting; and submeshes whose such
// vertices come within `distance` of each other go to different passes, so a pass never merges
// across submeshes. A relative margin of 1e-6 on the distance makes the plan safe for a merge
// comparing with < or <=. Greedy colouring in submesh id order. Reads positions,
// submesh_of_vertex (from find_submeshes); writes pass_of_vertex[vertex_count] (-1: nothing to
// merge at this vertex). Returns the number of passes (0: nothing to merge).
// Throws std::invalid_argument on a negative, NaN or infinite distance or a non-finite position.
size_t merge_passes(int32_t* pass_of_vertex, const float* positions, const int32_t* submesh_of_vertex,
                    size_t vertex_count, size_t submesh_count, const uint8_t* chosen, double distance, int threads);

// Merge by distance inside each chosen submesh. Vertices are visited by index; an unassigned one
// gathers every unassigned vertex of its submesh within `distance` (inclusive) into a cluster
// (clusters and merged positions match a host's k-d tree merge wherever clusters are unambiguous;
// which member survives may differ with the visiting order); the cluster's target is the lower index of two, else the
// member nearest the cluster's centroid (ties: lower index), and moves to the centroid. Reads
// positions, submesh_of_vertex, chosen[submesh_count]; writes target[vertex_count] (the vertex
// each merges into, itself for survivors) and merged_positions[vertex_count * 3] (positions,
// with targets at their centroids). Returns the number of vertices merged away.
// Throws std::invalid_argument on a negative, NaN or infinite distance or a non-finite position.
size_t merge_targets(int32_t* target, float* merged_positions, const float* positions, const int32_t* submesh_of_vertex,
                     size_t vertex_count, size_t submesh_count, const uint8_t* chosen, double distance, int threads);

// weld.cpp: the topology after merging vertices (the common case of a host's weld): in every face,
// a corner whose vertex merges into the next corner's vertex goes; faces left with fewer than 3
// corners go; edges are the distinct images of the old edges that do not collapse (first old
// edge wins); survivors keep their order. Old elements named by *_source arrays carry their
// attributes over. Output arrays have the input sizes as capacity.
struct WeldCounts {
    size_t vertices = 0, edges = 0, faces = 0, corners = 0;
    // True when the merge needs more than this weld does: a face would repeat a vertex at
    // non-adjacent corners (it must be split), two faces would become the same (one must go),
    // or a face edge would have no edge. The outputs are then incomplete and the caller must
    // merge another way.
    bool incomplete = false;
};

struct WeldOutput {
    int32_t* vertex_source;  // [vertex_count]
    int32_t* edge_source;    // [edge_count]
    int32_t* edges;          // [edge_count * 2], new vertex indices
    int32_t* face_source;    // [face_count]
    int32_t* face_starts;    // [face_count]
    int32_t* corner_source;  // [corner_count]
    int32_t* corner_verts;   // [corner_count], new vertex indices
    int32_t* corner_edges;   // [corner_count], new edge indices
};

// Reads mesh, corner_edges[corner_count] (each corner's edge to the next corner; may be null:
// then looked up from the new edges) and target[vertex_count] (from merge_targets). Throws
// std::invalid_argument (nothing written) when a target is not a surviving vertex or when faces
// name more corners than corner_count (overlapping faces).
WeldCounts weld_topology(const MeshView& mesh, const int32_t* corner_edges, const int32_t* target,
                         const WeldOutput& out);

// ---------------------------------------------------------------------------------------------
// pack_uv.cpp: UV islands packed in rows sorted by submesh height

struct PackUvOptions {
    double padding = 0.002;         // UV units between islands and at the square's border
    size_t max_per_row = 0;         // 0: as many as fit the width
    bool lock_overlapping = false;  // islands whose UV bounds overlap before packing move together
};

struct PackUvReport {
    size_t islands = 0;
    size_t groups = 0;  // units moved as one (islands, or overlapping sets when locked)
    size_t rows = 0;
    double scale = 0.0;  // uniform scale applied to every island
};

// Reads mesh (corner_verts, faces), face_mask[face_count] (null: every face), corner_uv
// [corner_count * 2] (in/out), vertex_height[vertex_count] (e.g. world Z) and
// submesh_of_vertex. Islands: selected faces joined where they share a vertex with equal UVs
// (within 1e-6). Each island takes the height of its submesh (centre of the submesh's height
// range); units are sorted highest first (ties: lowest face first) and placed in rows from the
// top of the unit square, left to right, at one uniform scale, the largest whose layout fits
// [0, 1] with `padding` between units and at the border. Writes corner_uv of selected faces
// only. Throws std::invalid_argument (nothing written) on non-finite UVs or heights, a padding
// outside [0, 0.5) or too large for the number of islands, or no selected face.
PackUvReport pack_uv_by_height(float* corner_uv, const MeshView& mesh, const uint8_t* face_mask,
                               const float* vertex_height, const int32_t* submesh_of_vertex, size_t submesh_count,
                               const PackUvOptions& options);

}  // namespace boxmarch
