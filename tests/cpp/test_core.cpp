// C++ tests of the native core's public header, without Python: contracts of every entry point,
// rejection of malformed input (nothing written), and the decode of a bake against boxes built
// here from known centres, sizes and rotations. Built with BOXMARCH_TESTS=ON and run by ctest,
// normally and in the sanitizer build (BOXMARCH_SANITIZE=ON). A tiny harness: CHECK records a
// failure and goes on; main returns nonzero when anything failed.
#include "boxmarch/boxmarch.h"
#include "owned_mesh.h"
#include "../../cpp/src/internal.h"  // group_by_submesh: internal, tested on its own

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

using namespace boxmarch;

namespace {

int failures = 0;
const char* current_test = "";

#define CHECK(cond)                                                                               \
    do {                                                                                          \
        if (!(cond)) {                                                                            \
            ++failures;                                                                           \
            std::fprintf(stderr, "FAIL %s (%s:%d): %s\n", current_test, __FILE__, __LINE__, #cond); \
        }                                                                                         \
    } while (0)

// True when fn throws std::invalid_argument whose message contains `words`.
bool rejects(const std::function<void()>& fn, const std::string& words) {
    try {
        fn();
    } catch (const std::invalid_argument& e) {
        if (std::string(e.what()).find(words) != std::string::npos) return true;
        std::fprintf(stderr, "  message was: %s\n", e.what());
        return false;
    }
    return false;
}

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major

Mat3 matrix_of_quaternion(double x, double y, double z, double w) {
    const double n = std::sqrt(x * x + y * y + z * z + w * w);
    x /= n, y /= n, z /= n, w /= n;
    return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
}

Vec3 apply(const Mat3& m, const Vec3& v) {
    return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
            m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

using Mesh = OwnedMesh;

struct Box {
    Vec3 centre, size;
    Mat3 rotation;
};

// Appends a box: vertex i of the unit cube has coordinates ((i >> 2) & 1, (i >> 1) & 1, i & 1) - 0.5,
// scaled, rotated and moved; 6 outward quads and 12 edges.
void add_box(Mesh& m, const Box& b) {
    const int32_t base = int32_t(m.positions.size() / 3);
    for (int i = 0; i < 8; ++i) {
        const Vec3 local = {(((i >> 2) & 1) - 0.5) * b.size[0], (((i >> 1) & 1) - 0.5) * b.size[1], ((i & 1) - 0.5) * b.size[2]};
        const Vec3 p = apply(b.rotation, local);
        for (int k = 0; k < 3; ++k) m.positions.push_back(float(p[k] + b.centre[k]));
    }
    static const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    static const int edges[12][2] = {{0, 1}, {1, 3}, {3, 2}, {2, 0}, {4, 5}, {5, 7}, {7, 6}, {6, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& q : quads) {
        m.face_starts.push_back(int32_t(m.corner_verts.size()));
        m.face_sizes.push_back(4);
        for (int c : q) m.corner_verts.push_back(base + c);
    }
    for (const auto& e : edges) {
        m.edges.push_back(base + e[0]);
        m.edges.push_back(base + e[1]);
    }
}

Mesh two_boxes() {
    Mesh m;
    add_box(m, {{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}, matrix_of_quaternion(0, 0, 0, 1)});
    add_box(m, {{3.0, 0.0, 0.0}, {1.0, 2.0, 3.0}, matrix_of_quaternion(0, 0, 0, 1)});
    return m;
}

// Output buffers of one bake, prefilled with markers so untouched entries can be seen.
struct Outputs {
    std::vector<int32_t> submesh_of_vertex;
    size_t count = 0;
    std::vector<uint32_t> fingerprints;
    std::vector<float> offset_float, quaternions, scales;
    std::vector<uint8_t> offset_byte, sources, statuses;
    std::vector<double> origins, half_extents;
    BakeOutput out;
    explicit Outputs(const MeshView& view)
        : submesh_of_vertex(view.vertex_count), fingerprints(view.vertex_count, 5u), offset_float(view.vertex_count * 4, -2.0f),
          quaternions(view.vertex_count * 4, -2.0f), scales(view.vertex_count, -2.0f), offset_byte(view.vertex_count * 4, 77),
          sources(view.vertex_count, 99), statuses(view.vertex_count, 99), origins(view.vertex_count * 3),
          half_extents(view.vertex_count * 3) {
        count = find_submeshes(submesh_of_vertex.data(), view);
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
    BakeReport bake(const MeshView& view, const BakeOptions& options, const uint32_t* previous = nullptr,
                    const uint8_t* mask = nullptr) {
        return boxmarch::bake(view, submesh_of_vertex.data(), count, mask, previous, options, out);
    }
    bool colours_untouched() const {
        for (float x : offset_float) if (x != -2.0f) return false;
        for (uint8_t x : offset_byte) if (x != 77) return false;
        for (uint32_t x : fingerprints) if (x != 5u) return false;
        return true;
    }
};

// The shader's decode of vertex v: position + rotate(f, q), f = (rgb * 2 - 1) / a, in double.
Vec3 decoded_origin(const Mesh& m, const Outputs& o, size_t v, bool bytes) {
    double c[4];
    for (int k = 0; k < 4; ++k) c[k] = bytes ? o.offset_byte[v * 4 + k] / 255.0 : o.offset_float[v * 4 + k];
    const Vec3 f = {(c[0] * 2 - 1) / c[3], (c[1] * 2 - 1) / c[3], (c[2] * 2 - 1) / c[3]};
    const float* q = &o.quaternions[size_t(o.submesh_of_vertex[v]) * 4];
    const Mat3 r = matrix_of_quaternion(q[0], q[1], q[2], q[3]);
    const Vec3 turned = apply(r, f);
    return {m.positions[v * 3] + turned[0], m.positions[v * 3 + 1] + turned[1], m.positions[v * 3 + 2] + turned[2]};
}

double distance(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// ---------------------------------------------------------------------------------------------

void test_validate_accepts_boxes_and_rejects_each_malformation() {
    const Mesh good = two_boxes();
    CHECK(!rejects([&] { validate_mesh(good.view()); }, ""));
    struct Case {
        const char* words;
        std::function<void(Mesh&)> spoil;
    };
    const Case cases[] = {
        {"vertex 3 has a NaN", [](Mesh& m) { m.positions[3 * 3 + 1] = std::numeric_limits<float>::quiet_NaN(); }},
        {"vertex 15 has a NaN or infinite", [](Mesh& m) { m.positions[15 * 3 + 2] = -std::numeric_limits<float>::infinity(); }},
        {"edge 5 names vertex 16", [](Mesh& m) { m.edges[5 * 2 + 1] = 16; }},
        {"edge 2 names vertex -1", [](Mesh& m) { m.edges[2 * 2] = -1; }},
        {"corner 7 names vertex 99", [](Mesh& m) { m.corner_verts[7] = 99; }},
        {"corner 0 names vertex -3", [](Mesh& m) { m.corner_verts[0] = -3; }},
        {"face 11 runs outside", [](Mesh& m) { m.face_sizes[11] = 5; }},
        {"face 0 runs outside", [](Mesh& m) { m.face_starts[0] = -1; }},
        {"face 4 runs outside", [](Mesh& m) { m.face_starts[4] = std::numeric_limits<int32_t>::max(); }},
        {"face 2 has fewer than 3", [](Mesh& m) { m.face_sizes[2] = 2; }},
        {"face 2 has fewer than 3", [](Mesh& m) { m.face_sizes[2] = -4; }},
    };
    for (const Case& c : cases) {
        Mesh bad = good;
        c.spoil(bad);
        CHECK(rejects([&] { validate_mesh(bad.view()); }, c.words));
    }
    MeshView missing = good.view();
    missing.positions = nullptr;
    CHECK(rejects([&] { validate_mesh(missing); }, "positions are missing"));
    missing = good.view();
    missing.corner_verts = nullptr;
    CHECK(rejects([&] { validate_mesh(missing); }, "corner vertices are missing"));
    MeshView too_many = good.view();
    too_many.vertex_count = size_t(INT32_MAX) + 1;
    CHECK(rejects([&] { validate_mesh(too_many); }, "too many vertices"));
}

void test_find_submeshes_numbers_by_lowest_vertex() {
    // Vertices 0..7; a triangle (6, 2, 4), an edge (5, 1), a triangle (3, 5, 0); 7 is loose.
    Mesh m;
    m.positions.assign(8 * 3, 0.0f);
    for (int v = 0; v < 8; ++v) m.positions[v * 3] = float(v);
    m.edges = {5, 1};
    m.face_starts = {0, 3};
    m.face_sizes = {3, 3};
    m.corner_verts = {6, 2, 4, 3, 5, 0};
    std::vector<int32_t> ids(8, -1);
    CHECK(find_submeshes(ids.data(), m.view()) == 3);
    CHECK((ids == std::vector<int32_t>{0, 0, 1, 0, 1, 0, 1, 2}));
}

void test_face_starts_from_corner_edges_recovers_faces_and_rejects_bad_indices() {
    // Two boxes: each corner's edge joins it to the next corner of its face, looked up here.
    const Mesh m = two_boxes();
    std::vector<int32_t> corner_edges(m.corner_verts.size(), -1);
    for (size_t f = 0; f < m.face_starts.size(); ++f)
        for (int32_t c = 0; c < m.face_sizes[f]; ++c) {
            const int32_t a = m.corner_verts[size_t(m.face_starts[f] + c)];
            const int32_t b = m.corner_verts[size_t(m.face_starts[f] + (c + 1) % m.face_sizes[f])];
            for (size_t e = 0; e < m.edges.size() / 2; ++e)
                if ((m.edges[2 * e] == a && m.edges[2 * e + 1] == b) || (m.edges[2 * e] == b && m.edges[2 * e + 1] == a))
                    corner_edges[size_t(m.face_starts[f] + c)] = int32_t(e);
        }
    std::vector<int32_t> starts(m.corner_verts.size() / 3 + 1, -1);
    const size_t count = face_starts_from_corner_edges(starts.data(), m.corner_verts.data(), corner_edges.data(),
                                                       m.corner_verts.size(), m.edges.data(), m.edges.size() / 2, 16);
    CHECK(count == 12);
    for (size_t f = 0; f < 12; ++f) CHECK(starts[f] == int32_t(4 * f));

    std::vector<int32_t> bad = corner_edges;
    bad[9] = 24;  // one past the last edge
    CHECK(rejects([&] {
        face_starts_from_corner_edges(starts.data(), m.corner_verts.data(), bad.data(), m.corner_verts.size(),
                                      m.edges.data(), m.edges.size() / 2, 16);
    }, "corner 9 names an edge out of range"));
    CHECK(rejects([&] {
        face_starts_from_corner_edges(starts.data(), m.corner_verts.data(), corner_edges.data(), m.corner_verts.size(),
                                      m.edges.data(), m.edges.size() / 2, 15);  // vertex 15 is then out of range
    }, "names a vertex out of range"));
}

void test_group_by_submesh_sorted_and_scattered() {
    const int32_t sorted[] = {0, 0, 1, 1, 1, 3};
    std::vector<uint32_t> offsets(5), items(6);
    group_by_submesh(offsets.data(), items.data(), sorted, 6, 4);
    CHECK((offsets == std::vector<uint32_t>{0, 2, 5, 5, 6}));
    CHECK((items == std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
    const int32_t scattered[] = {2, 0, 2, 1, 0};
    std::vector<uint32_t> o2(4), i2(5);
    group_by_submesh(o2.data(), i2.data(), scattered, 5, 3);
    CHECK((o2 == std::vector<uint32_t>{0, 2, 3, 5}));
    CHECK((i2 == std::vector<uint32_t>{1, 4, 3, 0, 2}));
}

void test_group_by_submesh_rejects_ids_out_of_range() {
    const int32_t too_large[] = {0, 3, 1};
    const int32_t negative[] = {0, -1, 1};
    std::vector<uint32_t> offsets(4, 9u), items(3, 9u);
    CHECK(rejects([&] { group_by_submesh(offsets.data(), items.data(), too_large, 3, 3); }, "item 1"));
    CHECK(rejects([&] { group_by_submesh(offsets.data(), items.data(), negative, 3, 3); }, "item 1"));
    CHECK((items == std::vector<uint32_t>{9u, 9u, 9u}));
}

void test_axis_turns_are_the_24_proper_signed_permutations() {
    std::vector<std::array<double, 9>> seen;
    for (int i = 0; i < 24; ++i) {
        std::array<double, 9> m;
        CHECK(axis_turn_matrix(m.data(), i));
        // Column-major: column c = m[c*3 .. c*3+2]. One +-1 per row and column, det +1.
        for (int c = 0; c < 3; ++c) {
            int nonzero = 0;
            for (int r = 0; r < 3; ++r) nonzero += m[c * 3 + r] != 0.0;
            CHECK(nonzero == 1);
        }
        const double det = m[0] * (m[4] * m[8] - m[7] * m[5]) - m[3] * (m[1] * m[8] - m[7] * m[2]) + m[6] * (m[1] * m[5] - m[4] * m[2]);
        CHECK(det == 1.0);
        for (const auto& other : seen) CHECK(other != m);
        seen.push_back(m);
    }
    double identity[9];
    axis_turn_matrix(identity, 0);
    CHECK(identity[0] == 1 && identity[4] == 1 && identity[8] == 1 && identity[1] == 0 && identity[3] == 0);
    double m[9];
    CHECK(!axis_turn_matrix(m, -1));
    CHECK(!axis_turn_matrix(m, 24));
    CHECK(!axis_turn_matrix(m, std::numeric_limits<int>::min()));
}

// Boxes of known centre, size and rotation: the decoded origin at every vertex is the box centre
// (up to float32 storage of the vertices), the quaternion is unit with w >= 0, and the half-extents
// are the box's.
void test_bake_decodes_box_centres(ColorEncoding encoding) {
    Mesh m;
    const Box boxes[] = {
        {{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}, matrix_of_quaternion(0.1, 0.7, -0.3, 0.5)},
        {{100.0, -50.0, 7.0}, {0.2, 0.9, 0.5}, matrix_of_quaternion(-0.8, 0.1, 0.2, 0.05)},
        {{-1000.0, 1000.0, 10.0}, {40.0, 15.0, 25.0}, matrix_of_quaternion(0.3, -0.3, 0.6, -0.6)},
        {{0.5, 0.5, 0.5}, {0.01, 0.02, 0.03}, matrix_of_quaternion(0.0, 0.0, 1.0, 0.0)},  // half turn: w = 0
    };
    for (const Box& b : boxes) add_box(m, b);
    const MeshView view = m.view();
    Outputs o(view);
    CHECK(o.count == 4);
    BakeOptions options;
    options.encoding = encoding;
    const BakeReport report = o.bake(view, options);
    CHECK(report.baked == 4 && report.degenerate == 0);
    const bool bytes = encoding == ColorEncoding::Byte;
    double worst_tolerance = 0.0;
    for (size_t s = 0; s < 4; ++s) {
        const float* q = &o.quaternions[s * 4];
        const double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
        CHECK(std::abs(norm - 1.0) < 1e-6);
        CHECK(q[3] >= 0.0f);
        const double half = 0.5 * std::max({boxes[s].size[0], boxes[s].size[1], boxes[s].size[2]});
        double largest = 0.0;
        for (int k = 0; k < 3; ++k) largest = std::max(largest, o.half_extents[s * 3 + k]);
        // float32 storage moves each coordinate by up to |x| 2^-24
        const double storage = 4.0 * 1000.0 * std::ldexp(1.0, -24);
        CHECK(std::abs(largest - half) <= storage + 1e-6 * half);
        // 8-bit: the decoded offset moves by about one byte step 2 / (255 a) per component.
        const double tolerance = bytes ? std::sqrt(3.0) * 2.0 / (255.0 * o.scales[s]) : 1e-5 * half;
        for (size_t v = s * 8; v < s * 8 + 8; ++v)
            CHECK(distance(decoded_origin(m, o, v, bytes), boxes[s].centre) <= tolerance + storage);
        worst_tolerance = std::max(worst_tolerance, tolerance);
    }
    CHECK(report.max_error <= worst_tolerance);
    if (!bytes) CHECK(report.max_relative_error <= 1e-5);
}

void test_bake_rejects_bad_options_and_numbering_and_writes_nothing() {
    const Mesh m = two_boxes();
    const MeshView view = m.view();
    const double bad_epsilons[] = {0.0, -0.1, 1e-8, std::nextafter(kAngleEpsilonMin, 0.0), M_PI / 2, 2.0,
                                   std::numeric_limits<double>::quiet_NaN()};
    for (double eps : bad_epsilons) {
        Outputs o(view);
        BakeOptions options;
        options.angle_epsilon = eps;
        CHECK(rejects([&] { o.bake(view, options); }, "angle_epsilon"));
        CHECK(o.colours_untouched());
    }
    for (int turn : {-1, 24, 1000}) {
        Outputs o(view);
        BakeOptions options;
        options.axis_turn = turn;
        CHECK(rejects([&] { o.bake(view, options); }, "axis_turn"));
        CHECK(o.colours_untouched());
    }
    {
        Outputs o(view);
        o.submesh_of_vertex[9] = 2;  // only 2 submeshes
        CHECK(rejects([&] { o.bake(view, BakeOptions()); }, "submesh_of_vertex"));
        o.submesh_of_vertex[9] = -1;
        CHECK(rejects([&] { o.bake(view, BakeOptions()); }, "submesh_of_vertex"));
        CHECK(o.colours_untouched());
    }
    {
        // A count larger than the numbering uses: submesh 2 would have no vertex.
        Outputs o(view);
        o.count = 3;
        CHECK(rejects([&] { o.bake(view, BakeOptions()); }, "submesh_of_vertex"));
        CHECK(o.colours_untouched());
    }
    {
        Outputs o(view);
        BakeOptions options;
        options.encoding = ColorEncoding::Byte;
        CHECK(rejects([&] {
            BakeOutput no_byte_colour = o.out;
            no_byte_colour.offset_byte = nullptr;
            boxmarch::bake(view, o.submesh_of_vertex.data(), o.count, nullptr, nullptr, options, no_byte_colour);
        }, "no output array"));
        CHECK(o.colours_untouched());
    }
}

void test_rebake_with_previous_fingerprints_skips_and_a_moved_box_is_baked() {
    Mesh m = two_boxes();
    Outputs first(m.view());
    first.bake(m.view(), BakeOptions());
    for (uint32_t f : first.fingerprints) CHECK(f != 0);
    Outputs second(m.view());
    BakeReport r = second.bake(m.view(), BakeOptions(), first.fingerprints.data());
    CHECK(r.unchanged == 2 && r.baked == 0);
    CHECK(second.offset_float[0] == -2.0f);  // unchanged submeshes keep their colours
    m.positions[9 * 3] += 0.5f;              // move one vertex of the second box
    Outputs third(m.view());
    r = third.bake(m.view(), BakeOptions(), first.fingerprints.data());
    CHECK(r.unchanged == 1 && r.baked == 1);
    CHECK(third.statuses[0] == uint8_t(SubmeshStatus::Unchanged) && third.statuses[1] == uint8_t(SubmeshStatus::Baked));
    const uint8_t mask[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0};
    Outputs fourth(m.view());
    r = fourth.bake(m.view(), BakeOptions(), nullptr, mask);
    CHECK(r.not_selected == 1 && r.baked == 1);
    for (size_t v = 0; v < 8; ++v) CHECK(fourth.fingerprints[v] == 0);  // never baked: 0
}

void test_expand_corner_quaternions_writes_pairs_and_rejects_bad_indices() {
    const int32_t corner_verts[] = {0, 2, 1, 2};
    const int32_t submesh_of_vertex[] = {1, 0, 1};
    const float quaternions[] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f};
    std::vector<float> uv(8, -1.0f);
    expand_corner_quaternions(uv.data(), 1, corner_verts, 4, submesh_of_vertex, 3, quaternions, 2, nullptr);
    CHECK((uv == std::vector<float>{0.7f, 0.8f, 0.7f, 0.8f, 0.3f, 0.4f, 0.7f, 0.8f}));
    const uint8_t write[] = {1, 0};
    std::vector<float> partial(8, -1.0f);
    expand_corner_quaternions(partial.data(), 0, corner_verts, 4, submesh_of_vertex, 3, quaternions, 2, write);
    CHECK((partial == std::vector<float>{-1.0f, -1.0f, -1.0f, -1.0f, 0.1f, 0.2f, -1.0f, -1.0f}));

    std::vector<float> untouched(8, -1.0f);
    CHECK(rejects([&] { expand_corner_quaternions(untouched.data(), 2, corner_verts, 4, submesh_of_vertex, 3, quaternions, 2, nullptr); }, "half"));
    const int32_t bad_corner[] = {0, 3, 1, 2};
    CHECK(rejects([&] { expand_corner_quaternions(untouched.data(), 0, bad_corner, 4, submesh_of_vertex, 3, quaternions, 2, nullptr); }, "corner 1"));
    const int32_t bad_submesh[] = {1, 2, 1};
    CHECK(rejects([&] { expand_corner_quaternions(untouched.data(), 0, corner_verts, 4, bad_submesh, 3, quaternions, 2, nullptr); }, "submesh_of_vertex"));
    CHECK((untouched == std::vector<float>(8, -1.0f)));
}

void test_options_seed_depends_on_every_output_option() {
    const BakeOptions base;
    std::vector<uint32_t> seeds = {options_seed(base)};
    BakeOptions o = base;
    o.angle_epsilon = 0.2;
    seeds.push_back(options_seed(o));
    o = base;
    o.origin = OriginMode::Mean;
    seeds.push_back(options_seed(o));
    o = base;
    o.sort_axes_by_extent = true;
    seeds.push_back(options_seed(o));
    o = base;
    o.axis_turn = 5;
    seeds.push_back(options_seed(o));
    o = base;
    o.encoding = ColorEncoding::Byte;
    seeds.push_back(options_seed(o));
    for (size_t i = 0; i < seeds.size(); ++i)
        for (size_t j = i + 1; j < seeds.size(); ++j) CHECK(seeds[i] != seeds[j]);
    o = base;
    o.threads = 7;  // does not change the output
    o.use_cache = false;
    CHECK(options_seed(o) == options_seed(base));
}

void test_reduce_per_submesh_majority_ties_and_rejections() {
    // submesh 0: 1, 1, 2 (majority 1, disagrees); 1: 5, 4 (tie: the lowest element's 5); 2: none
    const float values[] = {1, 2, 1, 5, 4};
    const int32_t ids[] = {0, 0, 0, 1, 1};
    float out[3] = {-1, -1, -1};
    uint8_t disagrees[3] = {9, 9, 9};
    CHECK(reduce_per_submesh(out, disagrees, values, 5, 1, ids, 3) == 2);
    CHECK(out[0] == 1 && out[1] == 5 && out[2] == 0);
    CHECK(disagrees[0] == 1 && disagrees[1] == 1 && disagrees[2] == 0);
    const float bad[] = {1, std::numeric_limits<float>::quiet_NaN()};
    float untouched[2] = {7, 7};
    CHECK(rejects([&] { reduce_per_submesh(untouched, nullptr, bad, 2, 1, ids, 1); }, "NaN"));
    CHECK(rejects([&] { reduce_per_submesh(untouched, nullptr, values, 1, 5, ids, 1); }, "components"));
    const int32_t out_of_range[] = {0, 3};
    CHECK(rejects([&] { reduce_per_submesh(untouched, nullptr, values, 2, 1, out_of_range, 2); }, "names submesh 3"));
    CHECK(untouched[0] == 7 && untouched[1] == 7);
}

void test_box_random_is_a_function_of_fingerprint_and_seed() {
    const uint32_t fingerprints[] = {1, 2, 1};
    float a[3], b[3];
    box_random(a, fingerprints, 3, 0);
    box_random(b, fingerprints, 3, 1);
    CHECK(a[0] == a[2] && a[0] != a[1] && a[0] != b[0]);
    for (float v : a) CHECK(v >= 0.0f && v < 1.0f && v * 16777216.0f == std::floor(v * 16777216.0f));
}

void test_box_hierarchy_rules_depths_and_cycles() {
    // Boxes along x at 0, 1, 2, 3 (unit half-extents for 0, smaller for the others).
    const double origins[] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0.5, 0, 0};
    const float q[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double half[] = {1, 1, 1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2};
    int32_t parent[4], depth[4];
    CHECK(box_hierarchy(parent, depth, origins, q, half, 4, HierarchyRule::Chain, nullptr) == 2);
    CHECK(parent[0] == -1 && parent[1] == 0 && parent[2] == 1 && parent[3] == 0);
    CHECK(depth[0] == 0 && depth[1] == 1 && depth[2] == 2 && depth[3] == 1);
    // Containment: 1 (origin x = 1, on box 0's face) and 3 lie in box 0; 2 in none.
    CHECK(box_hierarchy(parent, depth, origins, q, half, 4, HierarchyRule::Containment, nullptr) == 1);
    CHECK(parent[0] == -1 && parent[1] == 0 && parent[2] == -1 && parent[3] == 0);
    const int32_t cycle[] = {1, 2, 0, -1};
    int32_t kept[4] = {5, 5, 5, 5};
    CHECK(rejects([&] { box_hierarchy(kept, kept, origins, q, half, 4, HierarchyRule::Given, cycle); }, "cycle"));
    const int32_t self[] = {-1, 1, -1, -1};
    CHECK(rejects([&] { box_hierarchy(kept, kept, origins, q, half, 4, HierarchyRule::Given, self); }, "own parent"));
    const int32_t far[] = {-1, 4, -1, -1};
    CHECK(rejects([&] { box_hierarchy(kept, kept, origins, q, half, 4, HierarchyRule::Given, far); }, "outside"));
    CHECK(kept[0] == 5 && kept[3] == 5);
}

}  // namespace

int main() {
    struct Test {
        const char* name;
        std::function<void()> run;
    };
    const Test tests[] = {
        {"validate", test_validate_accepts_boxes_and_rejects_each_malformation},
        {"find_submeshes", test_find_submeshes_numbers_by_lowest_vertex},
        {"face_starts_from_corner_edges", test_face_starts_from_corner_edges_recovers_faces_and_rejects_bad_indices},
        {"group_by_submesh", test_group_by_submesh_sorted_and_scattered},
        {"group_by_submesh_rejects", test_group_by_submesh_rejects_ids_out_of_range},
        {"axis_turns", test_axis_turns_are_the_24_proper_signed_permutations},
        {"bake_float", [] { test_bake_decodes_box_centres(ColorEncoding::Float); }},
        {"bake_byte", [] { test_bake_decodes_box_centres(ColorEncoding::Byte); }},
        {"bake_rejects", test_bake_rejects_bad_options_and_numbering_and_writes_nothing},
        {"incremental", test_rebake_with_previous_fingerprints_skips_and_a_moved_box_is_baked},
        {"expand_corner_quaternions", test_expand_corner_quaternions_writes_pairs_and_rejects_bad_indices},
        {"options_seed", test_options_seed_depends_on_every_output_option},
        {"reduce_per_submesh", test_reduce_per_submesh_majority_ties_and_rejections},
        {"box_random", test_box_random_is_a_function_of_fingerprint_and_seed},
        {"box_hierarchy", test_box_hierarchy_rules_depths_and_cycles},
    };
    for (const Test& t : tests) {
        current_test = t.name;
        const int before = failures;
        t.run();
        std::printf("%s %s\n", failures == before ? "ok  " : "FAIL", t.name);
    }
    std::printf("%d failure(s)\n", failures);
    return failures ? 1 : 0;
}
