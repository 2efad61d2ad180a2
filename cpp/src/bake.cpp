// The bake: per submesh, frame (fresh or from the copy cache), optional axis sort and turn,
// origin, offsets, colour encoding, quaternion and the decode check. Submeshes are independent,
// so they are split across threads in fixed contiguous ranges (the output never depends on the
// thread count; only which copies hit the per-thread caches does).
// Based on the design of "rasterized ray marching at scale" (blog post, 11 June 2025): each
// submesh's origin and face-derived orientation stored in its vertices' colour and UV maps.
#include "internal.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

namespace {

// Relative tolerance of the copy cache: a copy may deviate from an exact similar image of the
// stored submesh by this fraction of its rms radius (room for float32 rounding of far copies).
constexpr double kCacheTolerance = 1e-5;

// The vertices, faces and edges of every submesh as index lists (CSR). Meshes almost always store
// submeshes one after another; then each list is a run of the ascending sequence 0, 1, 2, ...
// and only the offsets take memory, which keeps the bake's peak low on large meshes.
struct Grouped {
    std::vector<uint32_t> vertex_offsets, face_offsets, edge_offsets;
    std::vector<uint32_t> ascending, vertex_items, face_items, edge_items;
    const uint32_t *vertices = nullptr, *faces = nullptr, *edges = nullptr;
};

// Groups items by owner(i) into offsets; returns the list to use: items, or ascending when the
// owners are already in order.
template <class Owner>
const uint32_t* group_items(std::vector<uint32_t>& offsets, std::vector<uint32_t>& items,
                            const std::vector<uint32_t>& ascending, size_t item_count, size_t submesh_count,
                            Owner&& owner) {
    offsets.resize(submesh_count + 1);
    if (count_by_owner(offsets.data(), item_count, submesh_count, owner)) return ascending.data();
    items.resize(item_count);
    scatter_by_owner(items.data(), offsets.data(), item_count, submesh_count, owner);
    return items.data();
}

void group(Grouped& g, const MeshView& mesh, const int32_t* submesh_of_vertex, size_t submesh_count) {
    g.ascending.resize(std::max({mesh.vertex_count, mesh.face_count, mesh.edge_count}));
    std::iota(g.ascending.begin(), g.ascending.end(), 0u);
    g.vertices = group_items(g.vertex_offsets, g.vertex_items, g.ascending, mesh.vertex_count, submesh_count,
                             [&](size_t v) { return submesh_of_vertex[v]; });
    g.faces = group_items(g.face_offsets, g.face_items, g.ascending, mesh.face_count, submesh_count,
                          [&](size_t f) { return submesh_of_vertex[mesh.corner_verts[mesh.face_starts[f]]]; });
    g.edges = group_items(g.edge_offsets, g.edge_items, g.ascending, mesh.edge_count, submesh_count,
                          [&](size_t e) { return submesh_of_vertex[mesh.edges[2 * e]]; });
}

// Local coordinates of every vertex in `frame`; writes their bounds.
void local_bounds(const SubmeshView& s, const glm::dmat3& frame, std::vector<glm::dvec3>& local, glm::dvec3& lo,
                  glm::dvec3& hi) {
    const glm::dmat3 to_local = glm::transpose(frame);
    lo = glm::dvec3(INFINITY);
    hi = glm::dvec3(-INFINITY);
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        local[i] = to_local * s.position(s.vertices[i]);
        lo = glm::min(lo, local[i]);
        hi = glm::max(hi, local[i]);
    }
}

// Reorders the axes so extents fall from x to z, keeping the frame right-handed. Extents are
// compared on a logarithmic grid of tie-band steps, a transitive tie: extents in one step keep
// their axis order, so float noise cannot swap the axes of a cube.
glm::dmat3 sort_by_extent(const glm::dmat3& frame, const glm::dvec3& extent) {
    int64_t step[3];
    for (int k = 0; k < 3; ++k)
        step[k] = extent[k] > 0.0 ? std::llround(std::log(extent[k]) / std::log1p(kTieBand)) : INT64_MIN;
    int order[3] = {0, 1, 2};
    std::stable_sort(order, order + 3, [&](int a, int b) { return step[a] > step[b]; });
    const glm::dvec3 x = frame[order[0]], y = frame[order[1]];
    return glm::dmat3(x, y, glm::cross(x, y));
}

constexpr uint8_t kUncached = 0xFF;

// Cache routing of the submeshes to bake: kUncached for one whose key no other has (it cannot
// have a copy), else the thread that owns its key, so every copy meets its prototype in that
// thread's cache.
std::vector<uint8_t> route_by_key(const std::vector<uint64_t>& keys, const std::vector<uint8_t>& statuses,
                                  size_t threads) {
    const auto baked = [&](size_t sm) { return statuses[sm] == uint8_t(SubmeshStatus::Baked); };
    size_t slots = 16;
    while (slots < 2 * keys.size()) slots *= 2;
    std::vector<uint64_t> table(slots);
    std::vector<uint8_t> seen(slots, 0);  // 0 empty, 1 one submesh, 2 several
    auto slot_of = [&](uint64_t key) {
        size_t i = size_t(key ^ (key >> 29)) & (slots - 1);
        while (seen[i] && table[i] != key) i = (i + 1) & (slots - 1);
        return i;
    };
    for (size_t sm = 0; sm < keys.size(); ++sm) {
        if (!baked(sm)) continue;
        const size_t i = slot_of(keys[sm]);
        table[i] = keys[sm];
        seen[i] = seen[i] ? 2 : 1;
    }
    std::vector<uint8_t> route(keys.size(), kUncached);
    for (size_t sm = 0; sm < keys.size(); ++sm)
        if (baked(sm) && seen[slot_of(keys[sm])] == 2) route[sm] = uint8_t(keys[sm] % threads);
    return route;
}

struct Accumulated {
    size_t baked = 0, cache_hits = 0, unchanged = 0, not_selected = 0, degenerate = 0;
    double max_error = 0.0, max_relative_error = 0.0;
};

}  // namespace

uint32_t options_seed(const BakeOptions& o) {
    uint64_t h = 0x243F6A8885A308D3ull;
    auto add = [&](uint64_t x) {
        h = (h ^ x) * 0x100000001B3ull;
        h ^= h >> 29;
    };
    uint64_t eps_bits;
    static_assert(sizeof eps_bits == sizeof o.angle_epsilon, "double is 64-bit");
    std::memcpy(&eps_bits, &o.angle_epsilon, sizeof eps_bits);
    add(eps_bits);
    add(uint64_t(o.origin));
    add(uint64_t(o.sort_axes_by_extent));
    add(uint64_t(o.axis_turn));
    add(uint64_t(o.encoding));
    add(6);  // format version: bump when the bake's output changes for the same options
    return uint32_t(h ^ (h >> 32));
}

namespace {

// What every submesh of one bake shares: the mesh grouped by submesh, the options and outputs.
struct BakeJob {
    const MeshView& mesh;
    const Grouped& grouped;
    const uint8_t* bake_mask;
    const uint32_t* previous_fingerprints;
    const BakeOptions& options;
    const BakeOutput& out;
    glm::dmat3 turn_matrix;
    double cos_epsilon;
    uint32_t seed;
    bool bytes;

    SubmeshView view(size_t sm) const {
        const Grouped& g = grouped;
        SubmeshView s{&mesh,
                      g.vertices + g.vertex_offsets[sm],
                      g.vertex_offsets[sm + 1] - g.vertex_offsets[sm],
                      g.faces + g.face_offsets[sm],
                      g.face_offsets[sm + 1] - g.face_offsets[sm],
                      g.edges + g.edge_offsets[sm],
                      g.edge_offsets[sm + 1] - g.edge_offsets[sm],
                      glm::dvec3(0.0)};
        const float* p0 = mesh.positions + size_t(s.vertices[0]) * 3;
        s.base = glm::dvec3(p0[0], p0[1], p0[2]);
        return s;
    }
};

void check_bake_arguments(const MeshView& mesh, const int32_t* submesh_of_vertex, size_t submesh_count,
                          const BakeOptions& options, const BakeOutput& out) {
    if (!(options.angle_epsilon >= kAngleEpsilonMin && options.angle_epsilon <= kAngleEpsilonMax)) {
        char message[120];
        std::snprintf(message, sizeof message, "angle_epsilon must be in [%g, %.7g] radians, got %.9g",
                      kAngleEpsilonMin, kAngleEpsilonMax, options.angle_epsilon);
        throw std::invalid_argument(message);
    }
    if (options.axis_turn < 0 || options.axis_turn >= 24) throw std::invalid_argument("axis_turn must be in 0..23");
    const bool bytes = options.encoding == ColorEncoding::Byte;
    if (bytes ? !out.offset_byte : !out.offset_float)
        throw std::invalid_argument("no output array for the chosen colour encoding");
    if (!out.quaternions || !out.fingerprints)
        throw std::invalid_argument("quaternion and fingerprint outputs are required");
    if (first_out_of_range(submesh_of_vertex, mesh.vertex_count, submesh_count) < mesh.vertex_count)
        throw std::invalid_argument("submesh_of_vertex does not match submesh_count");
}

// Pass 1 for one submesh: its fingerprint and whether it is baked, left unchanged or not
// selected; writes its fingerprints, and zeros (source Identity) as the results of one not baked.
SubmeshStatus classify_submesh(const BakeJob& job, size_t sm, const SubmeshView& s, std::vector<uint32_t>& words) {
    const uint32_t fp = fingerprint_submesh(s, job.seed, words);
    const uint32_t* previous = job.previous_fingerprints;
    bool selected = !job.bake_mask, unchanged = previous != nullptr;
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const uint32_t v = s.vertices[i];
        selected = selected || job.bake_mask[v];
        unchanged = unchanged && previous[v] == fp;
    }
    // A submesh left out keeps its old fingerprint (0: never baked), so a later bake cannot
    // mistake it for one already baked.
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const uint32_t v = s.vertices[i];
        job.out.fingerprints[v] = selected ? fp : previous ? previous[v] : 0;
    }
    const SubmeshStatus status = !selected   ? SubmeshStatus::NotSelected
                                 : unchanged ? SubmeshStatus::Unchanged
                                             : SubmeshStatus::Baked;
    if (status == SubmeshStatus::Baked) return status;
    const BakeOutput& out = job.out;
    std::fill(out.quaternions + sm * 4, out.quaternions + sm * 4 + 4, 0.0f);
    if (out.origins) std::fill(out.origins + sm * 3, out.origins + sm * 3 + 3, 0.0);
    if (out.half_extents) std::fill(out.half_extents + sm * 3, out.half_extents + sm * 3 + 3, 0.0);
    if (out.scales) out.scales[sm] = 0.0f;
    if (out.sources) out.sources[sm] = uint8_t(FrameSource::Identity);
    return status;
}

// Scratch one thread reuses from submesh to submesh.
struct BakeScratch {
    std::vector<glm::dvec3> local, offsets;
    FrameScratch frame;
};

// Pass 2 for one submesh with its frame chosen: axis sort and turn, origin, offsets (encoded
// into the colour output), quaternion, and the decode check of what was stored.
void bake_submesh(const BakeJob& job, size_t sm, const SubmeshView& s, const FrameChoice& choice,
                  const FrameScratch* measured, BakeScratch& scratch, Accumulated& acc) {
    const BakeOutput& out = job.out;
    const FrameSource source = frame_source(choice);
    if (source != FrameSource::Faces) ++acc.degenerate;
    if (out.sources) out.sources[sm] = uint8_t(source);

    glm::dmat3 frame = frame_from_choice(choice, s, measured);
    std::vector<glm::dvec3>& local = scratch.local;
    std::vector<glm::dvec3>& offsets = scratch.offsets;
    local.resize(s.vertex_count);
    offsets.resize(s.vertex_count);
    glm::dvec3 lo, hi;
    if (job.options.sort_axes_by_extent) {
        local_bounds(s, frame, local, lo, hi);
        frame = sort_by_extent(frame, hi - lo);
    }
    frame = frame * job.turn_matrix;
    local_bounds(s, frame, local, lo, hi);
    const glm::dvec3 half = 0.5 * (hi - lo);
    glm::dvec3 origin_local;  // origin relative to base, in local coordinates
    if (job.options.origin == OriginMode::Bounds) {
        origin_local = 0.5 * (lo + hi);
    } else {
        origin_local = glm::dvec3(0.0);
        for (uint32_t i = 0; i < s.vertex_count; ++i) origin_local += local[i];
        origin_local /= double(s.vertex_count);
    }
    for (uint32_t i = 0; i < s.vertex_count; ++i) offsets[i] = origin_local - local[i];
    const float scale = job.bytes ? encode_byte(offsets.data(), s.vertices, s.vertex_count, out.offset_byte)
                                  : encode_float(offsets.data(), s.vertices, s.vertex_count, out.offset_float);

    float* q_out = out.quaternions + sm * 4;
    const glm::dvec4 q = quaternion_from_frame(frame);
    for (int k = 0; k < 4; ++k) q_out[k] = float(q[k]);
    const glm::dvec3 origin = frame * origin_local;  // relative to base, object axes
    if (out.origins)
        for (int k = 0; k < 3; ++k) out.origins[sm * 3 + k] = s.base[k] + origin[k];
    if (out.half_extents)
        for (int k = 0; k < 3; ++k) out.half_extents[sm * 3 + k] = half[k];
    if (out.scales) out.scales[sm] = scale;

    // Decode what was stored, as a shader would, and measure the miss.
    double worst2 = 0.0;  // squared: one square root per submesh, not one per vertex
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const uint32_t v = s.vertices[i];
        const glm::dvec3 f = job.bytes ? decode_byte(out.offset_byte + size_t(v) * 4)
                                       : decode_float(out.offset_float + size_t(v) * 4);
        const glm::dvec3 miss = s.position(v) + rotate_vector(f, q_out) - origin;
        worst2 = std::max(worst2, glm::dot(miss, miss));
    }
    const double worst = std::sqrt(worst2);
    const double extent = std::max({half.x, half.y, half.z});
    // A box too small for its offsets to be encoded (denormal float32 positions) is as
    // unusable as one without a frame.
    if (source == FrameSource::Faces && extent > 0.0 && extent <= kSmallestEncodableOffset) ++acc.degenerate;
    acc.max_error = std::max(acc.max_error, worst);
    acc.max_relative_error = std::max(acc.max_relative_error, extent > 0.0 ? worst / extent : worst);
}

BakeReport sum_parts(const std::vector<Accumulated>& parts, size_t submesh_count) {
    BakeReport report;
    report.submesh_count = submesh_count;
    for (const Accumulated& a : parts) {
        report.baked += a.baked;
        report.cache_hits += a.cache_hits;
        report.unchanged += a.unchanged;
        report.not_selected += a.not_selected;
        report.degenerate += a.degenerate;
        report.max_error = std::max(report.max_error, a.max_error);
        report.max_relative_error = std::max(report.max_relative_error, a.max_relative_error);
    }
    return report;
}

}  // namespace

BakeReport bake(const MeshView& mesh, const int32_t* submesh_of_vertex, size_t submesh_count, const uint8_t* bake_mask,
                const uint32_t* previous_fingerprints, const BakeOptions& options, const BakeOutput& out) {
    check_bake_arguments(mesh, submesh_of_vertex, submesh_count, options, out);
    Grouped g;
    group(g, mesh, submesh_of_vertex, submesh_count);
    for (size_t sm = 0; sm < submesh_count; ++sm)  // every submesh needs a vertex to anchor it
        if (g.vertex_offsets[sm + 1] == g.vertex_offsets[sm])
            throw std::invalid_argument("submesh_of_vertex does not match submesh_count: submesh " +
                                        std::to_string(sm) + " has no vertex");
    double turn[9];
    axis_turn_matrix(turn, options.axis_turn);
    const BakeJob job{mesh,
                      g,
                      bake_mask,
                      previous_fingerprints,
                      options,
                      out,
                      glm::dmat3(turn[0], turn[1], turn[2], turn[3], turn[4], turn[5], turn[6], turn[7], turn[8]),
                      std::cos(options.angle_epsilon),
                      options_seed(options),
                      options.encoding == ColorEncoding::Byte};

    size_t threads = hardware_threads(options.threads);
    threads = std::min<size_t>({threads, 255, std::max<size_t>(1, submesh_count / 1024)});
    auto range = [&](size_t t) {
        return std::make_pair(submesh_count * t / threads, submesh_count * (t + 1) / threads);
    };
    std::vector<Accumulated> parts(threads);
    // Pass 1: fingerprints and what to do with each submesh; cache keys of those to bake.
    std::vector<uint8_t> statuses(submesh_count);
    std::vector<uint64_t> keys(options.use_cache ? submesh_count : 0);
    run_parallel(threads, [&](size_t thread) {
        std::vector<uint32_t> words;
        const auto [first, last] = range(thread);
        for (size_t sm = first; sm < last; ++sm) {
            const SubmeshView s = job.view(sm);
            const SubmeshStatus status = classify_submesh(job, sm, s, words);
            statuses[sm] = uint8_t(status);
            if (status == SubmeshStatus::Unchanged) ++parts[thread].unchanged;
            if (status == SubmeshStatus::NotSelected) ++parts[thread].not_selected;
            if (status == SubmeshStatus::Baked && options.use_cache) keys[sm] = CopyCache::key(s, spread_of(s));
        }
    });
    if (out.statuses) std::copy(statuses.begin(), statuses.end(), out.statuses);
    // Copies share a cache key, so only submeshes whose key another one has use the cache.
    std::vector<uint8_t> route;
    if (options.use_cache) route = route_by_key(keys, statuses, threads);

    // Pass 2: the frame of each submesh to bake (fresh, or from this thread's copy cache), then
    // the rest of its bake.
    run_parallel(threads, [&](size_t thread) {
        Accumulated& acc = parts[thread];
        CopyCache cache(kCacheTolerance);
        BakeScratch scratch;
        const auto [first, last] = range(thread);
        for (size_t sm = 0; sm < submesh_count; ++sm) {
            if (statuses[sm] != uint8_t(SubmeshStatus::Baked)) continue;
            const bool cached = !route.empty() && route[sm] != kUncached;
            if (cached ? route[sm] != thread : sm < first || sm >= last) continue;
            const SubmeshView s = job.view(sm);
            ++acc.baked;
            FrameChoice choice;
            const FrameScratch* measured = &scratch.frame;  // null once the choice comes from the cache
            if (!cached) {
                choice = choose_frame(s, job.cos_epsilon, 0.0, scratch.frame);
            } else {
                const Spread spread = spread_of(s);
                if (cache.lookup(s, spread, keys[sm], choice)) {
                    ++acc.cache_hits;
                    measured = nullptr;
                } else {
                    choice = choose_frame(s, job.cos_epsilon, cache.displacement(spread), scratch.frame);
                    cache.insert(s, spread, keys[sm], choice);
                }
            }
            bake_submesh(job, sm, s, choice, measured, scratch, acc);
        }
    });
    return sum_parts(parts, submesh_count);
}

void expand_corner_quaternions(float* corner_uv, int half, const int32_t* corner_verts, size_t corner_count,
                               const int32_t* submesh_of_vertex, size_t vertex_count, const float* quaternions,
                               size_t submesh_count, const uint8_t* write_submesh) {
    if (half != 0 && half != 1) throw std::invalid_argument("half must be 0 (x, y) or 1 (z, w)");
    const size_t bad_corner = first_out_of_range(corner_verts, corner_count, vertex_count);
    if (bad_corner < corner_count)
        throw std::invalid_argument("corner " + std::to_string(bad_corner) + " names a vertex out of range");
    if (first_out_of_range(submesh_of_vertex, vertex_count, submesh_count) < vertex_count)
        throw std::invalid_argument("submesh_of_vertex does not match submesh_count");
    const size_t k = half ? 2 : 0;
    for (size_t c = 0; c < corner_count; ++c) {
        const size_t sm = size_t(submesh_of_vertex[corner_verts[c]]);
        if (!write_submesh || write_submesh[sm])
            std::memcpy(corner_uv + 2 * c, quaternions + sm * 4 + k, 2 * sizeof(float));
    }
}

}  // namespace boxmarch
