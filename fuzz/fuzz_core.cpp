// libFuzzer target: arbitrary index and coordinate arrays into every public entry point of the core.
//
// Each input is decoded into small meshes and arrays whose indices may be negative or out of range,
// whose face sizes may be anything, and whose coordinates are either grid values (so coincident,
// collinear and coplanar points are common) or raw float bits (NaN, infinities, denormals, 3e38).
// Every entry point must either throw std::invalid_argument or return; sanitizers catch any read or
// write out of bounds, and the checks below catch invalid results (NaN written, non-unit
// quaternion, unchanged outputs after a rejected call). Arrays are exactly sized heap buffers so
// AddressSanitizer sees a single element of overrun.
//
// Built by CMake with BOXMARCH_FUZZ=ON (clang, -fsanitize=fuzzer); replayed over fuzz/corpus by
// fuzz_replay (BOXMARCH_TESTS=ON, any compiler) as a regression test.
#include "boxmarch/boxmarch.h"
#include "../tests/cpp/owned_mesh.h"
#include "../cpp/src/internal.h"  // group_by_submesh: internal, fuzzed on its own

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

using namespace boxmarch;

namespace {

// Reads the fuzzer's bytes front to back; past the end every read returns zero.
class Bytes {
public:
    Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
    uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
    uint32_t u32() {
        uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v |= uint32_t(byte()) << (8 * k);
        return v;
    }
    // Mostly small values around the valid range (negative and past-the-end included); sometimes
    // raw 32-bit values (INT32_MIN, INT32_MAX, ...).
    int32_t index(bool raw) {
        if (raw) return int32_t(u32());
        return int32_t(int8_t(byte()));
    }
    float coordinate(bool raw) {
        if (raw) {
            const uint32_t bits = u32();
            float f;
            std::memcpy(&f, &bits, sizeof f);
            return f;
        }
        return float(int8_t(byte())) * 0.25f;
    }

private:
    const uint8_t* data_;
    size_t size_;
    size_t at_ = 0;
};

std::string last_rejection;  // message of the last std::invalid_argument, for failure reports

[[noreturn]] void fail(const char* what) {
    std::fprintf(stderr, "fuzz_core: %s (last rejection: '%s')\n", what, last_rejection.c_str());
    std::abort();
}

// Calls fn; returns false when it threw std::invalid_argument (the one allowed failure).
template <class Fn>
bool accepted(Fn&& fn) {
    try {
        fn();
        return true;
    } catch (const std::invalid_argument& e) {
        last_rejection = e.what();
        return false;
    }
}

using FuzzMesh = OwnedMesh;

FuzzMesh read_mesh(Bytes& in, uint8_t flags) {
    const bool raw_coordinates = flags & 1, raw_indices = flags & 2;
    FuzzMesh m;
    m.positions.resize(size_t(in.byte() % 33) * 3);
    m.edges.resize(size_t(in.byte() % 33) * 2);
    const size_t faces = in.byte() % 17;
    m.face_starts.resize(faces);
    m.face_sizes.resize(faces);
    m.corner_verts.resize(in.byte() % 65);
    for (float& p : m.positions) p = in.coordinate(raw_coordinates);
    for (int32_t& e : m.edges) e = in.index(raw_indices);
    if (flags & 4) {  // faces laid out one after another, as Blender stores them
        int32_t start = 0;
        for (size_t f = 0; f < faces; ++f) {
            m.face_starts[f] = start;
            m.face_sizes[f] = 3 + in.byte() % 3;
            start += m.face_sizes[f];
        }
    } else {
        for (size_t f = 0; f < faces; ++f) {
            m.face_starts[f] = in.index(raw_indices);
            m.face_sizes[f] = in.index(raw_indices);
        }
    }
    for (int32_t& c : m.corner_verts) c = in.index(raw_indices);
    return m;
}

BakeOptions read_options(Bytes& in) {
    BakeOptions o;
    const uint8_t e = in.byte();
    // 0, 1e-8 and values past pi/2 are invalid and must be rejected; 0.1 is the default.
    o.angle_epsilon = e == 255 ? 0.1 : e == 254 ? 1e-8 : e * (1.7 / 253.0);
    o.origin = OriginMode(in.byte() % 2);
    o.sort_axes_by_extent = in.byte() & 1;
    o.axis_turn = int(int8_t(in.byte())) % 27;  // -26..26: valid is 0..23
    o.encoding = ColorEncoding(in.byte() % 2);
    o.use_cache = in.byte() & 1;
    o.threads = 1 + in.byte() % 2;
    return o;
}

struct BakeBuffers {
    std::vector<uint32_t> fingerprints;
    std::vector<float> offset_float, quaternions, scales;
    std::vector<uint8_t> offset_byte, sources, statuses;
    std::vector<double> origins, half_extents;
    BakeOutput out;
    // The required outputs get one spare element when empty (bake wants non-null pointers even
    // for an empty mesh); check_bake verifies the spare is never written.
    BakeBuffers(size_t vertex_count, size_t submesh_count)
        : fingerprints(std::max<size_t>(vertex_count, 1), 7u), offset_float(std::max<size_t>(vertex_count * 4, 1), 9.0f),
          quaternions(std::max<size_t>(submesh_count * 4, 1), 9.0f),
          scales(submesh_count, 9.0f), offset_byte(std::max<size_t>(vertex_count * 4, 1), 9), sources(submesh_count, 9),
          statuses(submesh_count, 9), origins(submesh_count * 3, 9.0), half_extents(submesh_count * 3, 9.0) {
        out.fingerprints = fingerprints.data();
        out.offset_float = offset_float.data();
        out.offset_byte = offset_byte.data();
        out.quaternions = quaternions.data();
        out.origins = origins.data();
        out.half_extents = half_extents.data();
        out.scales = scales.data();
        out.sources = sources.data();
        out.statuses = statuses.data();
    }
    bool untouched() const {
        for (uint32_t f : fingerprints) if (f != 7u) return false;
        for (float x : offset_float) if (x != 9.0f) return false;
        for (uint8_t x : offset_byte) if (x != 9) return false;
        for (float x : quaternions) if (x != 9.0f) return false;
        return true;
    }
};

// What a successful bake must have written: finite, unit quaternions with w >= 0 for baked
// submeshes, finite colours with a positive alpha, a finite report.
void check_bake(const BakeBuffers& b, const BakeReport& report, const BakeOptions& o,
                const int32_t* submesh_of_vertex, size_t vertex_count, size_t submesh_count) {
    if (report.submesh_count != submesh_count) fail("report.submesh_count differs from the count given");
    if (report.baked + report.unchanged + report.not_selected != submesh_count) fail("statuses do not add up");
    if (!std::isfinite(report.max_error) || !std::isfinite(report.max_relative_error)) fail("report error not finite");
    if ((vertex_count == 0 && (b.fingerprints[0] != 7u || b.offset_float[0] != 9.0f || b.offset_byte[0] != 9)) ||
        (submesh_count == 0 && b.quaternions[0] != 9.0f))
        fail("bake wrote into an empty output");
    for (size_t s = 0; s < submesh_count; ++s) {
        if (b.statuses[s] != uint8_t(SubmeshStatus::Baked)) continue;
        const float* q = &b.quaternions[s * 4];
        const double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
        if (!(std::abs(norm - 1.0) < 1e-5)) fail("baked quaternion is not unit");
        if (!(q[3] >= 0.0f)) fail("baked quaternion has w < 0");
        if (!(b.scales[s] > 0.0f) || !std::isfinite(b.scales[s])) fail("scale not positive and finite");
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(b.origins[s * 3 + k]) || !(b.half_extents[s * 3 + k] >= 0.0)) fail("origin or extent invalid");
    }
    for (size_t v = 0; v < vertex_count; ++v) {
        if (b.statuses[size_t(submesh_of_vertex[v])] != uint8_t(SubmeshStatus::Baked)) continue;
        if (b.fingerprints[v] == 0) fail("baked vertex got fingerprint 0");
        if (o.encoding == ColorEncoding::Float) {
            for (int k = 0; k < 4; ++k)
                if (!std::isfinite(b.offset_float[v * 4 + k])) fail("non-finite colour written");
            if (!(b.offset_float[v * 4 + 3] > 0.0f)) fail("float alpha not positive");
        } else if (b.offset_byte[v * 4 + 3] == 0) {
            fail("byte alpha 0 (decode would divide by zero)");
        }
    }
}

void fuzz_bake(Bytes& in, const FuzzMesh& m, const MeshView& view) {
    std::vector<int32_t> submesh_of_vertex(view.vertex_count);
    const size_t count = find_submeshes(submesh_of_vertex.data(), view);
    if (count > view.vertex_count) fail("more submeshes than vertices");
    for (int32_t id : submesh_of_vertex)
        if (id < 0 || size_t(id) >= count) fail("find_submeshes wrote an id out of range");

    const BakeOptions options = read_options(in);
    const uint8_t extras = in.byte();
    std::vector<uint8_t> mask;
    std::vector<uint32_t> previous;
    if (extras & 1) for (size_t v = 0; v < view.vertex_count; ++v) mask.push_back(in.byte() & 1);
    if (extras & 2) for (size_t v = 0; v < view.vertex_count; ++v) previous.push_back(in.byte() % 3);
    BakeBuffers b(view.vertex_count, count);
    BakeReport report;
    const bool ok = accepted([&] {
        report = bake(view, submesh_of_vertex.data(), count, mask.empty() ? nullptr : mask.data(),
                      previous.empty() ? nullptr : previous.data(), options, b.out);
    });
    const bool options_valid = options.angle_epsilon >= kAngleEpsilonMin && options.angle_epsilon <= kAngleEpsilonMax &&
                               options.axis_turn >= 0 && options.axis_turn < 24;
    if (ok != options_valid) fail(ok ? "bake accepted invalid options" : "bake rejected a valid mesh and options");
    if (!ok) {
        if (!b.untouched()) fail("rejected bake wrote output");
        return;
    }
    check_bake(b, report, options, submesh_of_vertex.data(), view.vertex_count, count);

    // Corner quaternions of what was baked, with every corner written.
    for (int half = 0; half < 2; ++half) {
        std::vector<float> uv(view.corner_count * 2, 0.0f);
        expand_corner_quaternions(uv.data(), half, m.corner_verts.data(), view.corner_count, submesh_of_vertex.data(),
                                  view.vertex_count, b.quaternions.data(), count, nullptr);
    }

    // The same bake again with its own fingerprints: everything selected is unchanged.
    if (mask.empty()) {
        BakeBuffers again(view.vertex_count, count);
        const BakeReport r2 = bake(view, submesh_of_vertex.data(), count, nullptr, b.fingerprints.data(), options,
                                   again.out);
        if (r2.unchanged != count || r2.baked != 0) fail("re-bake with its own fingerprints was not all unchanged");
    }
}

// bake with a caller-made submesh numbering that may be wrong: rejected or baked, never out of bounds.
void fuzz_bake_numbering(Bytes& in, const MeshView& view) {
    const size_t count = in.byte() % 9;
    std::vector<int32_t> submesh_of_vertex(view.vertex_count);
    for (int32_t& id : submesh_of_vertex) id = int32_t(int8_t(in.byte())) % 10;
    BakeOptions options;
    options.encoding = ColorEncoding(in.byte() % 2);
    BakeBuffers b(view.vertex_count, count);
    BakeReport report;
    if (!accepted([&] {
            report = bake(view, submesh_of_vertex.data(), count, nullptr, nullptr, options, b.out);
        })) {
        if (!b.untouched()) fail("bake with a rejected numbering wrote output");
    }
}

void fuzz_face_starts(Bytes& in, const FuzzMesh& m, const MeshView& view) {
    std::vector<int32_t> corner_edges(view.corner_count);
    const bool raw = in.byte() & 1;
    for (int32_t& e : corner_edges) e = in.index(raw);
    const size_t vertex_count = in.byte() % 40;
    std::vector<int32_t> starts(view.corner_count / 3 + 1, -7);
    size_t count = 0;
    if (accepted([&] {
            count = face_starts_from_corner_edges(starts.data(), m.corner_verts.data(), corner_edges.data(),
                                                  view.corner_count, m.edges.data(), view.edge_count, vertex_count);
        })) {
        const size_t written = count < starts.size() ? count : starts.size();
        for (size_t i = 0; i < written; ++i)
            if (starts[i] < 0 || size_t(starts[i]) >= view.corner_count || (i && starts[i] <= starts[i - 1]))
                fail("face_starts_from_corner_edges wrote an invalid start");
    } else {
        for (int32_t s : starts)
            if (s != -7) fail("rejected face_starts_from_corner_edges wrote output");
    }
}

void fuzz_group(Bytes& in) {
    const size_t item_count = in.byte() % 33, submesh_count = in.byte() % 9;
    std::vector<int32_t> submesh_of_item(item_count);
    for (int32_t& s : submesh_of_item) s = int32_t(int8_t(in.byte())) % 10;
    std::vector<uint32_t> offsets(submesh_count + 1, 7u), items(item_count, 7u);
    if (accepted([&] { group_by_submesh(offsets.data(), items.data(), submesh_of_item.data(), item_count, submesh_count); })) {
        if (offsets[0] != 0 || offsets[submesh_count] != item_count) fail("group_by_submesh offsets do not span the items");
        for (size_t s = 0; s < submesh_count; ++s)
            for (uint32_t i = offsets[s]; i < offsets[s + 1]; ++i)
                if (items[i] >= item_count || submesh_of_item[items[i]] != int32_t(s)) fail("item grouped under the wrong submesh");
    } else {
        for (uint32_t x : items) if (x != 7u) fail("rejected group_by_submesh wrote items");
    }
}

void fuzz_expand(Bytes& in) {
    const size_t corner_count = in.byte() % 33, vertex_count = in.byte() % 17, submesh_count = in.byte() % 9;
    const int half = int(in.byte() % 4) - 1;  // -1..2: valid is 0 and 1
    std::vector<int32_t> corner_verts(corner_count), submesh_of_vertex(vertex_count);
    for (int32_t& c : corner_verts) c = int32_t(int8_t(in.byte())) % 20;
    for (int32_t& s : submesh_of_vertex) s = int32_t(int8_t(in.byte())) % 10;
    std::vector<float> quaternions(submesh_count * 4, 0.5f), uv(corner_count * 2, 3.0f);
    std::vector<uint8_t> write(submesh_count);
    for (uint8_t& w : write) w = in.byte() & 1;
    const bool use_write = in.byte() & 1;
    if (!accepted([&] {
            expand_corner_quaternions(uv.data(), half, corner_verts.data(), corner_count, submesh_of_vertex.data(),
                                      vertex_count, quaternions.data(), submesh_count, use_write ? write.data() : nullptr);
        })) {
        for (float x : uv) if (x != 3.0f) fail("rejected expand_corner_quaternions wrote output");
    }
}

void fuzz_small_functions(Bytes& in) {
    const int index = int(int32_t(in.u32()));
    double m[9];
    if (axis_turn_matrix(m, index) != (index >= 0 && index < 24)) fail("axis_turn_matrix accepted an index outside 0..23");
    BakeOptions o;
    std::memcpy(&o.angle_epsilon, &index, sizeof index);  // arbitrary bits, options_seed must not care
    o.axis_turn = index;
    (void)options_seed(o);
}

MarchOptions read_march_options(Bytes& in) {
    MarchOptions o;
    o.sdf = SdfPreset(int(in.byte() % 9) - 1);  // -1..7: valid is 0..6
    o.max_steps = int(int8_t(in.byte()));       // negative is invalid
    const uint8_t e = in.byte();
    o.epsilon = e == 0 ? 0.0f : e == 1 ? -1e-3f : std::ldexp(1.0f, -int(e % 24));
    o.relaxation = (in.byte() % 26) * 0.1f;     // 0..2.5: valid is (0, 2]
    const uint8_t d = in.byte();
    o.max_distance = d == 0 ? 0.0f : float(d);
    o.threads = 1;
    return o;
}

bool march_options_valid(const MarchOptions& o) {
    return o.max_steps >= 0 && o.epsilon > 0.0f && o.relaxation > 0.0f && o.relaxation <= 2.0f &&
           o.max_distance > 0.0f && int(o.sdf) >= 0 && int(o.sdf) < kSdfPresetCount;
}

void fuzz_raymarch(Bytes& in) {
    const size_t rays = in.byte() % 9;
    const bool raw = in.byte() & 1;
    std::vector<float> origins(rays * 3), directions(rays * 3), half(rays * 3);
    for (float& x : origins) x = in.coordinate(raw);
    for (float& x : directions) x = in.coordinate(raw);
    for (float& x : half) x = in.coordinate(raw);
    const MarchOptions o = read_march_options(in);
    std::vector<uint8_t> hit(rays, 7);
    std::vector<float> positions(rays * 3, 7.0f), normals(rays * 3, 7.0f);
    std::vector<int32_t> steps(rays, -7);
    const bool ok = accepted([&] {
        raymarch(origins.data(), directions.data(), half.data(), rays, o, hit.data(), positions.data(), normals.data(),
                 steps.data());
    });
    bool directions_valid = true;  // a ray needs a direction: (0, 0, 0) is refused
    for (size_t i = 0; i < rays; ++i)
        directions_valid &= !(directions[3 * i] == 0.0f && directions[3 * i + 1] == 0.0f && directions[3 * i + 2] == 0.0f);
    if (ok != (march_options_valid(o) && directions_valid))
        fail(ok ? "raymarch accepted invalid options or a zero direction" : "raymarch rejected valid options");
    for (size_t i = 0; i < rays; ++i) {
        if (!ok) {
            if (hit[i] != 7 || steps[i] != -7) fail("rejected raymarch wrote output");
        } else if (hit[i] > 1 || steps[i] < 0 || steps[i] > o.max_steps) {
            fail("raymarch wrote a hit flag or step count out of range");
        }
    }
    if (rays) {
        float distance = 0.0f;
        const bool preset_ok = int(o.sdf) >= 0 && int(o.sdf) < kSdfPresetCount;
        if (accepted([&] { distance = sdf_distance(o.sdf, origins.data(), half.data()); }) != preset_ok)
            fail("sdf_distance disagrees with the preset range");
        (void)distance;
    }
}

void fuzz_render(Bytes& in) {
    const size_t boxes = in.byte() % 4;
    const uint32_t width = in.byte() % 17, height = in.byte() % 17;
    const bool raw = in.byte() & 1;
    std::vector<float> origins(boxes * 3), quaternions(boxes * 4), half(boxes * 3);
    for (float& x : origins) x = in.coordinate(raw);
    for (float& x : quaternions) x = in.coordinate(raw);
    for (float& x : half) x = in.coordinate(raw);
    float clip[16], view_matrix[16];
    for (float& x : clip) x = in.coordinate(raw);
    for (float& x : view_matrix) x = in.coordinate(raw);
    RenderView view;
    view.object_to_clip = clip;
    view.object_to_view = view_matrix;
    view.width = width;
    view.height = height;
    MarchOptions o = read_march_options(in);
    o.max_steps = o.max_steps % 33;  // keep one input cheap: pixels x boxes x steps
    const size_t pixels = size_t(width) * height;
    // One spare element when empty: render_boxes wants non-null images even with no pixels.
    std::vector<float> rgba(std::max<size_t>(pixels * 4, 1), 0.0f), depth(std::max<size_t>(pixels, 1), 1.0f),
        normals(pixels * 3, 0.0f);
    std::vector<int32_t> steps(pixels, 0);
    RenderImages images;
    images.rgba = rgba.data();
    images.depth = depth.data();
    images.normals = normals.data();
    images.steps = steps.data();
    const bool ok = accepted([&] { render_boxes(origins.data(), quaternions.data(), half.data(), boxes, view, o, images); });
    if (ok != march_options_valid(o)) fail(ok ? "render_boxes accepted invalid options" : "render_boxes rejected valid options");
    for (int32_t s : steps)
        if (s < 0) fail("render_boxes wrote a negative step count");
}

double read_distance(Bytes& in) {  // mostly small, sometimes invalid (negative, NaN, infinite)
    const uint8_t b = in.byte();
    if (b == 255) return std::nan("");
    if (b == 254) return -0.5;
    if (b == 253) return INFINITY;
    return (b % 64) * 0.0625;
}

// The submesh tools (issue 3), called as their contracts allow: with the numbering from
// find_submeshes (the Python bindings check caller-made numberings), arbitrary positions,
// distances, selections and UVs. The hash and k-d tree pair searches must agree exactly.
void fuzz_tools(Bytes& in, const FuzzMesh& m, const MeshView& view) {
    const size_t n = view.vertex_count;
    std::vector<int32_t> ids(n);
    const size_t count = find_submeshes(ids.data(), view);
    const double radius = read_distance(in);
    const bool grouped = in.byte() & 1;
    const size_t capacity = in.byte() % 40;
    std::vector<uint32_t> hash_pairs(std::max<size_t>(capacity * 2, 1)), tree_pairs(std::max<size_t>(capacity * 2, 1));
    size_t hash_count = 0, tree_count = 0;
    const bool hash_ok = accepted([&] {
        hash_count = find_close_pairs(hash_pairs.data(), capacity, m.positions.data(), n, radius,
                                      grouped ? ids.data() : nullptr, 1);
    });
    const bool tree_ok = accepted([&] {
        tree_count = find_close_pairs_kdtree(tree_pairs.data(), capacity, m.positions.data(), n, radius,
                                             grouped ? ids.data() : nullptr);
    });
    if (hash_ok != tree_ok) fail("hash and k-d tree pair searches disagree on accepting the input");
    if (hash_ok) {
        if (hash_count != tree_count) fail("hash and k-d tree pair searches found different pair counts");
        const size_t shown = std::min(hash_count, capacity);
        for (size_t i = 0; i < shown * 2; ++i)
            if (hash_pairs[i] != tree_pairs[i] || hash_pairs[i] >= n) fail("pair lists differ or name a vertex out of range");
    }

    std::vector<uint8_t> selected(n), out(n), chosen(count);
    for (uint8_t& x : selected) x = in.byte() & 1;
    for (uint8_t& x : chosen) x = in.byte() & 1;
    if (select_linked_submeshes(out.data(), selected.data(), ids.data(), n, count) > count)
        fail("select_linked_submeshes selected more submeshes than exist");
    const double epsilon = read_distance(in), tolerance = read_distance(in), distance = read_distance(in);
    size_t linked = 0;
    if (accepted([&] { linked = select_linked_across(out.data(), selected.data(), m.positions.data(), ids.data(), n, count, epsilon, 1); }) &&
        linked > count)
        fail("select_linked_across selected more submeshes than exist");
    std::vector<int32_t> duplicate_of(count, -7);
    if (accepted([&] { find_duplicate_submeshes(duplicate_of.data(), m.positions.data(), ids.data(), n, count, chosen.data(), tolerance, 1); }))
        for (size_t s = 0; s < count; ++s)
            if (duplicate_of[s] < -1 || duplicate_of[s] >= int32_t(s)) fail("duplicate_of names a later or invalid submesh");
    std::vector<int32_t> pass_of_vertex(n), target(n);
    std::vector<float> merged(n * 3);
    accepted([&] { merge_passes(pass_of_vertex.data(), m.positions.data(), ids.data(), n, count, chosen.data(), distance, 1); });
    if (accepted([&] { merge_targets(target.data(), merged.data(), m.positions.data(), ids.data(), n, count, chosen.data(), distance, 1); })) {
        for (size_t v = 0; v < n; ++v)
            if (target[v] < 0 || size_t(target[v]) >= n || ids[size_t(target[v])] != ids[v]) fail("merge target outside the submesh");
        const size_t e = view.edge_count, f = view.face_count, c = view.corner_count;
        std::vector<int32_t> vertex_source(n), edge_source(e), edges(e * 2), face_source(f), face_starts(f),
            corner_source(c), corner_verts(c), corner_edges(c);
        const WeldOutput w{vertex_source.data(), edge_source.data(), edges.data(), face_source.data(), face_starts.data(),
                           corner_source.data(), corner_verts.data(), corner_edges.data()};
        accepted([&] { weld_topology(view, nullptr, target.data(), w); });
    }
    std::vector<float> uv(view.corner_count * 2), height(n);
    const bool raw = in.byte() & 1;
    for (float& x : uv) x = in.coordinate(raw);
    for (float& x : height) x = in.coordinate(raw);
    std::vector<uint8_t> face_mask(view.face_count);
    for (uint8_t& x : face_mask) x = in.byte() & 1;
    PackUvOptions options;
    options.padding = (in.byte() % 8) * 0.1 - 0.1;  // -0.1..0.6: valid is [0, 0.5)
    options.max_per_row = in.byte() % 4;
    options.lock_overlapping = in.byte() & 1;
    std::vector<float> before = uv;
    if (accepted([&] { pack_uv_by_height(uv.data(), view, face_mask.data(), height.data(), ids.data(), count, options); })) {
        for (size_t f = 0; f < view.face_count; ++f)  // it writes (and checks) selected faces only
            for (int32_t k = 0; face_mask[f] && k < m.face_sizes[f]; ++k)
                for (int d = 0; d < 2; ++d)
                    if (!std::isfinite(uv[size_t(m.face_starts[f] + k) * 2 + d])) fail("pack_uv_by_height wrote a non-finite UV");
    } else if (!uv.empty() && std::memcmp(uv.data(), before.data(), uv.size() * sizeof(float)) != 0) {  // bits: NaN != NaN
        fail("rejected pack_uv_by_height wrote UVs");
    }
}

}  // namespace

void fuzz_box_params(Bytes& in) {
    const size_t element_count = in.byte() % 33, submesh_count = in.byte() % 9, components = in.byte() % 6;
    std::vector<int32_t> ids(element_count);
    for (int32_t& id : ids) id = int32_t(int8_t(in.byte())) % 10;
    std::vector<float> values(element_count * 5);
    for (float& v : values) {
        const uint32_t bits = in.byte() & 1 ? in.u32() : uint32_t(in.byte() % 3) << 23 | 0x3f000000u;
        std::memcpy(&v, &bits, sizeof v);  // raw bits (NaN, infinities) or a few repeated values
    }
    std::vector<float> out(submesh_count * 5, 7.0f);
    std::vector<uint8_t> disagrees(submesh_count, 7);
    size_t count = 0;
    if (accepted([&] {
            count = reduce_per_submesh(out.data(), disagrees.data(), values.data(), element_count, components, ids.data(),
                                       submesh_count);
        })) {
        size_t flagged = 0;
        for (uint8_t d : disagrees) flagged += d == 1;
        if (flagged != count) fail("reduce_per_submesh's count differs from its flags");
    } else {
        for (float x : out) if (x != 7.0f) fail("rejected reduce_per_submesh wrote values");
    }
    const uint32_t fingerprints[2] = {in.u32(), in.u32()};
    float random[2];
    box_random(random, fingerprints, 2, in.u32());
    for (float r : random) if (!(r >= 0.0f && r < 1.0f)) fail("box_random left [0, 1)");

    const size_t boxes = in.byte() % 9;
    const HierarchyRule rule = HierarchyRule(int(in.byte() % 5) - 1);  // -1..3: valid is 0..2
    std::vector<double> origins(boxes * 3), half(boxes * 3);
    std::vector<float> quaternions(boxes * 4);
    for (double& o : origins) o = double(int8_t(in.byte())) / 8.0;
    for (double& h : half) h = double(in.byte() % 5) / 4.0;
    for (size_t i = 0; i < boxes; ++i) quaternions[i * 4 + 3] = 1.0f;
    std::vector<int32_t> given(boxes), parent(boxes, 7), depth(boxes, 7);
    for (int32_t& g : given) g = int32_t(int8_t(in.byte())) % 10;
    const bool use_given = in.byte() & 1;
    if (accepted([&] {
            box_hierarchy(parent.data(), depth.data(), origins.data(), quaternions.data(), half.data(), boxes, rule,
                          use_given ? given.data() : nullptr);
        })) {
        for (size_t i = 0; i < boxes; ++i) {
            if (parent[i] < -1 || parent[i] >= int32_t(boxes) || parent[i] == int32_t(i)) fail("box_hierarchy wrote a bad parent");
            else if (depth[i] != (parent[i] < 0 ? 0 : depth[size_t(parent[i])] + 1)) fail("box_hierarchy's depth is not its parent's + 1");
        }
    } else {
        for (size_t i = 0; i < boxes; ++i)
            if (parent[i] != 7 || depth[i] != 7) fail("rejected box_hierarchy wrote output");
    }
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    Bytes in(data, size);
    const uint8_t flags = in.byte();
    const FuzzMesh m = read_mesh(in, flags);
    const MeshView view = m.view();
    if (accepted([&] { validate_mesh(view); })) {
        fuzz_bake(in, m, view);
        fuzz_bake_numbering(in, view);
        fuzz_tools(in, m, view);
    }
    fuzz_face_starts(in, m, view);
    fuzz_group(in);
    fuzz_expand(in);
    fuzz_small_functions(in);
    fuzz_raymarch(in);
    fuzz_render(in);
    fuzz_box_params(in);
    return 0;
}
