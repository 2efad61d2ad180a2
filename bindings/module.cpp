// boxmarch._core: NumPy arrays in and out of the native core, without copies. This file only
// checks arrays and moves them; every algorithm lives in cpp/.
#include "boxmarch/boxmarch.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <cstring>
#include <sstream>
#include <string>
#include <vector>
#include <algorithm>
#include <cmath>

namespace py = pybind11;
using namespace boxmarch;

namespace {

template <class T>
const char* dtype_name();
template <> const char* dtype_name<float>() { return "float32"; }
template <> const char* dtype_name<double>() { return "float64"; }
template <> const char* dtype_name<int32_t>() { return "int32"; }
template <> const char* dtype_name<uint32_t>() { return "uint32"; }
template <> const char* dtype_name<uint8_t>() { return "uint8"; }

std::string shape_of(const py::array& a) {
    std::ostringstream s;
    s << "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
    s << (a.ndim() == 1 ? ",)" : ")");
    return s.str();
}

// The array as a C-contiguous T array of shape (rows, cols) (cols 0: one dimension), or a
// ValueError saying what was expected and what came. rows < 0 accepts any row count.
template <class T>
py::array_t<T> checked(const py::object& obj, const char* name, py::ssize_t rows, py::ssize_t cols, bool writable = false) {
    if (!py::isinstance<py::array>(obj))
        throw py::value_error(std::string(name) + " must be a NumPy array");
    py::array a = py::reinterpret_borrow<py::array>(obj);
    const bool dtype_ok = a.dtype().is(py::dtype::of<T>()) || a.dtype().equal(py::dtype::of<T>());
    const bool shape_ok = cols ? (a.ndim() == 2 && a.shape(1) == cols) : a.ndim() == 1;
    const bool rows_ok = shape_ok && (rows < 0 || a.shape(0) == rows);
    if (!dtype_ok || !rows_ok || !(a.flags() & py::array::c_style) || (writable && !a.writeable())) {
        std::ostringstream s;
        s << name << " must be a C-contiguous" << (writable ? " writable " : " ") << dtype_name<T>()
          << " array of shape (" << (rows < 0 ? std::string("N") : std::to_string(rows));
        if (cols) s << ", " << cols;
        s << (cols ? ")" : ",)") << "; got " << py::str(a.dtype()).cast<std::string>() << " " << shape_of(a);
        if (!(a.flags() & py::array::c_style)) s << " (not C-contiguous)";
        throw py::value_error(s.str());
    }
    return py::reinterpret_borrow<py::array_t<T>>(a);
}

// Arrays of one mesh, kept alive while the view points into them.
struct MeshArrays {
    py::array_t<float> positions;
    py::array_t<int32_t> edges, face_starts, face_sizes, corner_verts;
    MeshView view;

    MeshArrays(const py::object& p, const py::object& e, const py::object& fs, const py::object& fz, const py::object& cv)
        : positions(checked<float>(p, "positions", -1, 3)),
          edges(checked<int32_t>(e, "edges", -1, 2)),
          face_starts(checked<int32_t>(fs, "face_starts", -1, 0)),
          face_sizes(checked<int32_t>(fz, "face_sizes", face_starts.shape(0), 0)),
          corner_verts(checked<int32_t>(cv, "corner_verts", -1, 0)) {
        view.positions = positions.data();
        view.vertex_count = size_t(positions.shape(0));
        view.edges = edges.data();
        view.edge_count = size_t(edges.shape(0));
        view.face_starts = face_starts.data();
        view.face_sizes = face_sizes.data();
        view.face_count = size_t(face_starts.shape(0));
        view.corner_verts = corner_verts.data();
        view.corner_count = size_t(corner_verts.shape(0));
        py::gil_scoped_release release;
        validate_mesh(view);
    }
};

template <class T>
py::array_t<T> empty(py::ssize_t rows, py::ssize_t cols = 0) {
    return cols ? py::array_t<T>({rows, cols}) : py::array_t<T>(rows);
}

constexpr size_t kTrimAfterVertices = size_t(1) << 20;

py::dict bake_py(const py::object& positions, const py::object& edges, const py::object& face_starts,
                 const py::object& face_sizes, const py::object& corner_verts, const py::object& mask,
                 const py::object& previous_fingerprints, const py::object& offsets_out, double angle_epsilon,
                 const std::string& origin, bool sort_axes_by_extent, int axis_turn, const std::string& encoding,
                 bool use_cache, int threads) {
    MeshArrays mesh(positions, edges, face_starts, face_sizes, corner_verts);
    const py::ssize_t n = py::ssize_t(mesh.view.vertex_count);
    BakeOptions options;
    options.angle_epsilon = angle_epsilon;
    if (origin == "BOUNDS") options.origin = OriginMode::Bounds;
    else if (origin == "MEAN") options.origin = OriginMode::Mean;
    else throw py::value_error("origin must be 'BOUNDS' or 'MEAN', got '" + origin + "'");
    if (encoding == "FLOAT_COLOR") options.encoding = ColorEncoding::Float;
    else if (encoding == "BYTE_COLOR") options.encoding = ColorEncoding::Byte;
    else throw py::value_error("encoding must be 'FLOAT_COLOR' or 'BYTE_COLOR', got '" + encoding + "'");
    options.sort_axes_by_extent = sort_axes_by_extent;
    options.axis_turn = axis_turn;
    options.use_cache = use_cache;
    options.threads = threads;
    const bool bytes = options.encoding == ColorEncoding::Byte;

    py::array_t<uint8_t> mask_arr;
    py::array_t<uint32_t> previous;
    if (!mask.is_none()) mask_arr = checked<uint8_t>(mask, "mask", n, 0);
    if (!previous_fingerprints.is_none()) previous = checked<uint32_t>(previous_fingerprints, "previous_fingerprints", n, 0);
    py::array offsets;
    if (offsets_out.is_none()) {
        offsets = bytes ? py::array(empty<uint8_t>(n, 4)) : py::array(empty<float>(n, 4));
        // Zeros where nothing is baked, as for the per-submesh arrays. Without a mask or previous
        // fingerprints every submesh is baked and every row is written.
        if (!mask.is_none() || !previous_fingerprints.is_none())
            std::memset(offsets.mutable_data(), 0, size_t(offsets.nbytes()));
    }
    else offsets = bytes ? py::array(checked<uint8_t>(offsets_out, "offsets", n, 4, true))
                         : py::array(checked<float>(offsets_out, "offsets", n, 4, true));

    py::array_t<int32_t> submesh_of_vertex = empty<int32_t>(n);
    py::array_t<uint32_t> fingerprints = empty<uint32_t>(n);
    size_t count;
    {
        py::gil_scoped_release release;
        count = find_submeshes(submesh_of_vertex.mutable_data(), mesh.view);
    }
    const py::ssize_t m = py::ssize_t(count);
    py::array_t<float> quaternions = empty<float>(m, 4), scales = empty<float>(m);
    py::array_t<double> origins = empty<double>(m, 3), half_extents = empty<double>(m, 3);
    py::array_t<uint8_t> sources = empty<uint8_t>(m), statuses = empty<uint8_t>(m);
    BakeOutput out;
    out.fingerprints = fingerprints.mutable_data();
    out.quaternions = quaternions.mutable_data();
    out.origins = origins.mutable_data();
    out.half_extents = half_extents.mutable_data();
    out.scales = scales.mutable_data();
    out.sources = sources.mutable_data();
    out.statuses = statuses.mutable_data();
    BakeReport report;
    {
        if (bytes) out.offset_byte = static_cast<uint8_t*>(offsets.mutable_data());
        else out.offset_float = static_cast<float*>(offsets.mutable_data());
        const uint8_t* mk = mask.is_none() ? nullptr : mask_arr.data();
        const uint32_t* pv = previous_fingerprints.is_none() ? nullptr : previous.data();
        py::gil_scoped_release release;
        report = bake(mesh.view, submesh_of_vertex.data(), count, mk, pv, options, out);
#ifdef __GLIBC__
        // glibc keeps the freed scratch of a large bake in its heaps; hand it back before Blender
        // allocates the layers the bake writes, or it adds to the peak of the whole operation.
        // Trimming walks every heap (milliseconds), so small bakes skip it.
        if (mesh.view.vertex_count >= kTrimAfterVertices) malloc_trim(0);
#endif
    }
    py::dict r;
    r["submesh_of_vertex"] = submesh_of_vertex;
    r["fingerprints"] = fingerprints;
    r["offsets"] = offsets;
    r["quaternions"] = quaternions;
    r["origins"] = origins;
    r["half_extents"] = half_extents;
    r["scales"] = scales;
    r["sources"] = sources;
    r["statuses"] = statuses;
    r["submesh_count"] = report.submesh_count;
    r["baked"] = report.baked;
    r["cache_hits"] = report.cache_hits;
    r["unchanged"] = report.unchanged;
    r["not_selected"] = report.not_selected;
    r["degenerate"] = report.degenerate;
    r["max_error"] = report.max_error;
    r["max_relative_error"] = report.max_relative_error;
    return r;
}

SdfPreset preset_of(int sdf) {
    if (sdf < 0 || sdf >= kSdfPresetCount)
        throw py::value_error("sdf must be a preset index 0.." + std::to_string(kSdfPresetCount - 1) + ", got " + std::to_string(sdf));
    return SdfPreset(sdf);
}

MarchOptions march_options(int sdf, int max_steps, float epsilon, float relaxation, float max_distance, int threads) {
    MarchOptions o;
    o.sdf = preset_of(sdf);
    o.max_steps = max_steps;
    o.epsilon = epsilon;
    o.relaxation = relaxation;
    o.max_distance = max_distance;
    o.threads = threads;
    return o;
}

// A row-major (4, 4) NumPy matrix as the 16 column-major floats GLM reads.
std::vector<float> column_major(const py::object& m, const char* name) {
    auto a = checked<float>(m, name, 4, 4);
    std::vector<float> c(16);
    for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) c[size_t(k * 4 + r)] = a.data()[r * 4 + k];
    for (float v : c)
        if (!std::isfinite(v)) throw py::value_error(std::string(name) + " has a non-finite entry");
    return c;
}

// ---- submesh tools ----

// submesh_of_vertex as int32[vertex_count]; the core checks the ids' range.
py::array_t<int32_t> checked_submeshes(const py::object& obj, py::ssize_t vertex_count) {
    return checked<int32_t>(obj, "submesh_of_vertex", vertex_count, 0);
}

py::array_t<uint32_t> close_pairs_py(const py::object& positions, double radius, const py::object& groups,
                                     const std::string& method, int threads) {
    auto p = checked<float>(positions, "positions", -1, 3);
    const size_t n = size_t(p.shape(0));
    py::array_t<int32_t> g;
    if (!groups.is_none()) g = checked<int32_t>(groups, "groups", p.shape(0), 0);
    const int32_t* gp = groups.is_none() ? nullptr : g.data();
    if (method != "HASH" && method != "KDTREE")
        throw py::value_error("method must be 'HASH' or 'KDTREE', got '" + method + "'");
    std::vector<uint32_t> out(2 * n);
    size_t total;
    auto run = [&](size_t capacity) {
        py::gil_scoped_release release;
        return method == "HASH" ? find_close_pairs(out.data(), capacity, p.data(), n, radius, gp, threads)
                                : find_close_pairs_kdtree(out.data(), capacity, p.data(), n, radius, gp);
    };
    total = run(n);
    if (total > n) {
        out.resize(2 * total);
        run(total);
    }
    py::array_t<uint32_t> result({py::ssize_t(total), py::ssize_t(2)});
    std::copy(out.begin(), out.begin() + 2 * total, result.mutable_data());
    return result;
}

py::dict pack_uv_py(const py::object& corner_uv, const py::object& positions, const py::object& edges,
                    const py::object& face_starts, const py::object& face_sizes, const py::object& corner_verts,
                    const py::object& face_mask, const py::object& vertex_height, const py::object& submesh_of_vertex,
                    size_t submesh_count, double padding, size_t max_per_row, bool lock_overlapping) {
    MeshArrays mesh(positions, edges, face_starts, face_sizes, corner_verts);
    auto uv = checked<float>(corner_uv, "corner_uv", py::ssize_t(mesh.view.corner_count), 2, true);
    const py::ssize_t n = py::ssize_t(mesh.view.vertex_count);
    auto height = checked<float>(vertex_height, "vertex_height", n, 0);
    auto ids = checked_submeshes(submesh_of_vertex, n);
    py::array_t<uint8_t> mask;
    if (!face_mask.is_none()) mask = checked<uint8_t>(face_mask, "face_mask", py::ssize_t(mesh.view.face_count), 0);
    PackUvOptions options;
    options.padding = padding;
    options.max_per_row = max_per_row;
    options.lock_overlapping = lock_overlapping;
    PackUvReport report;
    {
        const uint8_t* mp = face_mask.is_none() ? nullptr : mask.data();
        float* out = uv.mutable_data();
        py::gil_scoped_release release;
        report = pack_uv_by_height(out, mesh.view, mp, height.data(), ids.data(), submesh_count, options);
    }
    py::dict r;
    r["islands"] = report.islands;
    r["groups"] = report.groups;
    r["rows"] = report.rows;
    r["scale"] = report.scale;
    return r;
}

// Mesh checks and submeshes.
void bind_mesh(py::module_& m) {
    m.def("validate_mesh", [](const py::object& p, const py::object& e, const py::object& fs, const py::object& fz,
                              const py::object& cv) { MeshArrays mesh(p, e, fs, fz, cv); },
          py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"), py::arg("corner_verts"),
          "Raise ValueError naming the first malformed element of the mesh arrays.");

    m.def("find_submeshes", [](const py::object& p, const py::object& e, const py::object& fs, const py::object& fz,
                               const py::object& cv) {
              MeshArrays mesh(p, e, fs, fz, cv);
              py::array_t<int32_t> ids = empty<int32_t>(py::ssize_t(mesh.view.vertex_count));
              size_t count;
              {
                  py::gil_scoped_release release;
                  count = find_submeshes(ids.mutable_data(), mesh.view);
              }
              return py::make_tuple(ids, count);
          },
          py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"), py::arg("corner_verts"),
          "Connected components: (submesh_of_vertex int32[N], count), numbered by lowest vertex.");

    m.def("face_starts_from_corner_edges",
          [](const py::object& corner_verts, const py::object& corner_edges, const py::object& edges, size_t vertex_count) {
              auto cv = checked<int32_t>(corner_verts, "corner_verts", -1, 0);
              auto ce = checked<int32_t>(corner_edges, "corner_edges", cv.shape(0), 0);
              auto e = checked<int32_t>(edges, "edges", -1, 2);
              std::vector<int32_t> starts(size_t(cv.shape(0)) / 3 + 1);
              size_t count;
              {
                  py::gil_scoped_release release;
                  count = face_starts_from_corner_edges(starts.data(), cv.data(), ce.data(), size_t(cv.shape(0)),
                                                        e.data(), size_t(e.shape(0)), vertex_count);
              }
              py::array_t<int32_t> result(py::ssize_t(std::min(count, starts.size())));
              std::copy(starts.begin(), starts.begin() + result.shape(0), result.mutable_data());
              return py::make_tuple(result, count);
          },
          py::arg("corner_verts"), py::arg("corner_edges"), py::arg("edges"), py::arg("vertex_count"),
          "(face_starts int32, count): face boundaries recovered from corner edges; compare count with the real face count.");
}

// The bake and its corner expansion.
void bind_bake(py::module_& m) {
    m.def("bake", &bake_py, py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"),
          py::arg("corner_verts"), py::kw_only(), py::arg("mask") = py::none(),
          py::arg("previous_fingerprints") = py::none(), py::arg("offsets") = py::none(),
          py::arg("angle_epsilon") = 0.1, py::arg("origin") = "BOUNDS", py::arg("sort_axes_by_extent") = false,
          py::arg("axis_turn") = 0, py::arg("encoding") = "FLOAT_COLOR", py::arg("use_cache") = true,
          py::arg("threads") = 0, "Bake every submesh; see boxmarch.core.bake.");

    m.def("expand_corner_quaternions",
          [](const py::object& corner_uv, int half, const py::object& corner_verts, const py::object& submesh_of_vertex,
             const py::object& quaternions, const py::object& write_submesh) {
              auto cv = checked<int32_t>(corner_verts, "corner_verts", -1, 0);
              auto uv = checked<float>(corner_uv, "corner_uv", cv.shape(0), 2, true);
              auto sv = checked<int32_t>(submesh_of_vertex, "submesh_of_vertex", -1, 0);
              auto q = checked<float>(quaternions, "quaternions", -1, 4);
              py::array_t<uint8_t> w;
              if (!write_submesh.is_none()) w = checked<uint8_t>(write_submesh, "write_submesh", q.shape(0), 0);
              const uint8_t* wp = write_submesh.is_none() ? nullptr : w.data();
              float* out = uv.mutable_data();
              py::gil_scoped_release release;
              expand_corner_quaternions(out, half, cv.data(), size_t(cv.shape(0)), sv.data(), size_t(sv.shape(0)),
                                        q.data(), size_t(q.shape(0)), wp);
          },
          py::arg("corner_uv"), py::arg("half"), py::arg("corner_verts"), py::arg("submesh_of_vertex"),
          py::arg("quaternions"), py::arg("write_submesh") = py::none(),
          "Fill corner_uv (float32[C, 2]) in place with each corner's (q.x, q.y) (half=0) or (q.z, q.w) (half=1).");

    m.def("axis_turn_matrices", []() {
        py::array_t<double> all({24, 3, 3});
        double* d = all.mutable_data();
        for (int i = 0; i < 24; ++i) {
            double col_major[9];
            axis_turn_matrix(col_major, i);
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) d[i * 9 + r * 3 + c] = col_major[c * 3 + r];
        }
        return all;
    }, "The 24 axis-aligned turns as row-major 3x3 matrices; column i is the new local axis i in the derived frame.");
}

// The CPU reference raymarcher and renderer.
void bind_raymarch(py::module_& m) {
    m.def("raymarch",
          [](const py::object& origins, const py::object& directions, const py::object& half_extents, int sdf,
             int max_steps, float epsilon, float relaxation, float max_distance, int threads) {
              auto ro = checked<float>(origins, "origins", -1, 3);
              auto rd = checked<float>(directions, "directions", ro.shape(0), 3);
              auto h = checked<float>(half_extents, "half_extents", ro.shape(0), 3);
              MarchOptions o = march_options(sdf, max_steps, epsilon, relaxation, max_distance, threads);
              const py::ssize_t n = ro.shape(0);
              py::array_t<uint8_t> hit = empty<uint8_t>(n);
              py::array_t<float> positions = empty<float>(n, 3), normals = empty<float>(n, 3);
              py::array_t<int32_t> steps = empty<int32_t>(n);
              {
                  uint8_t* hp = hit.mutable_data();
                  float* pp = positions.mutable_data();
                  float* np_ = normals.mutable_data();
                  int32_t* sp = steps.mutable_data();
                  py::gil_scoped_release release;
                  raymarch(ro.data(), rd.data(), h.data(), size_t(n), o, hp, pp, np_, sp);
              }
              py::dict r;
              r["hit"] = hit;
              r["positions"] = positions;
              r["normals"] = normals;
              r["steps"] = steps;
              return r;
          },
          py::arg("origins"), py::arg("directions"), py::arg("half_extents"), py::kw_only(), py::arg("sdf"),
          py::arg("max_steps"), py::arg("epsilon"), py::arg("relaxation"), py::arg("max_distance"), py::arg("threads") = 0,
          "Sphere-trace box-local rays; see boxmarch.core.raymarch.");

    m.def("render_boxes",
          [](const py::object& origins, const py::object& quaternions, const py::object& half_extents,
             const py::object& object_to_clip, const py::object& object_to_view, const py::object& base_color,
             const py::object& rgba, const py::object& depth, const py::object& normals, const py::object& steps,
             int sdf, int max_steps, float epsilon, float relaxation, float max_distance, int threads) {
              auto c = checked<float>(origins, "origins", -1, 3);
              auto q = checked<float>(quaternions, "quaternions", c.shape(0), 4);
              auto h = checked<float>(half_extents, "half_extents", c.shape(0), 3);
              auto color = checked<float>(base_color, "base_color", 3, 0);
              if (!py::isinstance<py::array>(depth) || py::reinterpret_borrow<py::array>(depth).ndim() != 2)
                  throw py::value_error("depth must be a float32 array of shape (height, width)");
              const py::ssize_t height = py::reinterpret_borrow<py::array>(depth).shape(0);
              const py::ssize_t width = py::reinterpret_borrow<py::array>(depth).shape(1);
              auto d = checked<float>(depth, "depth", height, width, true);
              auto image = checked<float>(rgba, "rgba", height * width, 4, true);
              py::array_t<float> nrm;
              py::array_t<int32_t> st;
              if (!normals.is_none()) nrm = checked<float>(normals, "normals", height * width, 3, true);
              if (!steps.is_none()) st = checked<int32_t>(steps, "steps", height * width, 0, true);
              std::vector<float> clip = column_major(object_to_clip, "object_to_clip");
              std::vector<float> view_m = column_major(object_to_view, "object_to_view");
              MarchOptions o = march_options(sdf, max_steps, epsilon, relaxation, max_distance, threads);
              RenderView view;
              view.object_to_clip = clip.data();
              view.object_to_view = view_m.data();
              view.width = uint32_t(width);
              view.height = uint32_t(height);
              for (int k = 0; k < 3; ++k) view.base_color[k] = color.data()[k];
              RenderImages images;
              images.rgba = image.mutable_data();
              images.depth = d.mutable_data();
              images.normals = normals.is_none() ? nullptr : nrm.mutable_data();
              images.steps = steps.is_none() ? nullptr : st.mutable_data();
              py::gil_scoped_release release;
              render_boxes(c.data(), q.data(), h.data(), size_t(c.shape(0)), view, o, images);
          },
          py::arg("origins"), py::arg("quaternions"), py::arg("half_extents"), py::arg("object_to_clip"),
          py::arg("object_to_view"), py::arg("base_color"), py::arg("rgba"), py::arg("depth"), py::arg("normals"),
          py::arg("steps"), py::kw_only(), py::arg("sdf"), py::arg("max_steps"), py::arg("epsilon"),
          py::arg("relaxation"), py::arg("max_distance"), py::arg("threads") = 0,
          "Raymarch boxes into caller-owned images (rgba (H*W, 4), depth (H, W), normals (H*W, 3), steps (H*W,)); "
          "see boxmarch.core.render_boxes.");

    m.def("sdf_distance",
          [](int sdf, const py::object& points, const py::object& half_extents) {
              auto p = checked<float>(points, "points", -1, 3);
              auto h = checked<float>(half_extents, "half_extents", p.shape(0), 3);
              const SdfPreset preset = preset_of(sdf);
              py::array_t<float> d = empty<float>(p.shape(0));
              for (py::ssize_t i = 0; i < p.shape(0); ++i)
                  d.mutable_data()[i] = sdf_distance(preset, p.data() + 3 * i, h.data() + 3 * i);
              return d;
          },
          py::arg("sdf"), py::arg("points"), py::arg("half_extents"), "Distances of box-local points to a preset.");
    // ---- submesh tools ----
}

// Close pairs, the two selection tools and dedup.
void bind_selection_tools(py::module_& m) {
    m.def("find_close_pairs", &close_pairs_py, py::arg("positions"), py::arg("radius"), py::kw_only(),
          py::arg("groups") = py::none(), py::arg("method") = "HASH", py::arg("threads") = 0,
          "uint32 (P, 2): every pair i < j within radius (inclusive), sorted; see boxmarch.core.find_close_pairs.");

    m.def("select_linked_submeshes",
          [](const py::object& selected, const py::object& submesh_of_vertex, size_t submesh_count) {
              auto sel = checked<uint8_t>(selected, "selected", -1, 0);
              auto ids = checked_submeshes(submesh_of_vertex, sel.shape(0));
              py::array_t<uint8_t> out = empty<uint8_t>(sel.shape(0));
              size_t count;
              {
                  uint8_t* o = out.mutable_data();
                  py::gil_scoped_release release;
                  count = select_linked_submeshes(o, sel.data(), ids.data(), size_t(sel.shape(0)), submesh_count);
              }
              return py::make_tuple(out, count);
          },
          py::arg("selected"), py::arg("submesh_of_vertex"), py::arg("submesh_count"),
          "(uint8 mask per vertex, submeshes selected): every submesh with a selected vertex, whole.");

    m.def("select_linked_across",
          [](const py::object& positions, const py::object& selected, const py::object& submesh_of_vertex,
             size_t submesh_count, double epsilon, int threads) {
              auto p = checked<float>(positions, "positions", -1, 3);
              auto sel = checked<uint8_t>(selected, "selected", p.shape(0), 0);
              auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
              py::array_t<uint8_t> out = empty<uint8_t>(p.shape(0));
              size_t count;
              {
                  uint8_t* o = out.mutable_data();
                  py::gil_scoped_release release;
                  count = select_linked_across(o, sel.data(), p.data(), ids.data(), size_t(p.shape(0)), submesh_count,
                                               epsilon, threads);
              }
              return py::make_tuple(out, count);
          },
          py::arg("positions"), py::arg("selected"), py::arg("submesh_of_vertex"), py::arg("submesh_count"),
          py::arg("epsilon"), py::arg("threads") = 0,
          "(uint8 mask per vertex, submeshes selected): flood fill through edges and vertices within epsilon.");

    m.def("find_duplicate_submeshes",
          [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
             const py::object& candidate, double tolerance, int threads) {
              auto p = checked<float>(positions, "positions", -1, 3);
              auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
              py::array_t<uint8_t> cand;
              if (!candidate.is_none()) cand = checked<uint8_t>(candidate, "candidate", py::ssize_t(submesh_count), 0);
              py::array_t<int32_t> out = empty<int32_t>(py::ssize_t(submesh_count));
              size_t count;
              {
                  const uint8_t* cp = candidate.is_none() ? nullptr : cand.data();
                  int32_t* o = out.mutable_data();
                  py::gil_scoped_release release;
                  count = find_duplicate_submeshes(o, p.data(), ids.data(), size_t(p.shape(0)), submesh_count, cp,
                                                   tolerance, threads);
              }
              return py::make_tuple(out, count);
          },
          py::arg("positions"), py::arg("submesh_of_vertex"), py::arg("submesh_count"), py::arg("candidate"),
          py::arg("tolerance"), py::arg("threads") = 0,
          "(duplicate_of int32 per submesh, -1 where kept; number of duplicates).");
}

// Merge per submesh and the weld.
void bind_merge_tools(py::module_& m) {
    m.def("merge_passes",
          [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
             const py::object& chosen, double distance, int threads) {
              auto p = checked<float>(positions, "positions", -1, 3);
              auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
              auto ch = checked<uint8_t>(chosen, "chosen", py::ssize_t(submesh_count), 0);
              py::array_t<int32_t> out = empty<int32_t>(p.shape(0));
              size_t passes;
              {
                  int32_t* o = out.mutable_data();
                  py::gil_scoped_release release;
                  passes = merge_passes(o, p.data(), ids.data(), size_t(p.shape(0)), submesh_count, ch.data(),
                                        distance, threads);
              }
              return py::make_tuple(out, passes);
          },
          py::arg("positions"), py::arg("submesh_of_vertex"), py::arg("submesh_count"), py::arg("chosen"),
          py::arg("distance"), py::arg("threads") = 0,
          "(pass_of_vertex int32, -1 where nothing merges; number of passes).");

    m.def("merge_targets",
          [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
             const py::object& chosen, double distance, int threads) {
              auto p = checked<float>(positions, "positions", -1, 3);
              auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
              auto ch = checked<uint8_t>(chosen, "chosen", py::ssize_t(submesh_count), 0);
              py::array_t<int32_t> target = empty<int32_t>(p.shape(0));
              py::array_t<float> merged = empty<float>(p.shape(0), 3);
              size_t count;
              {
                  int32_t* t = target.mutable_data();
                  float* m = merged.mutable_data();
                  py::gil_scoped_release release;
                  count = merge_targets(t, m, p.data(), ids.data(), size_t(p.shape(0)), submesh_count, ch.data(),
                                        distance, threads);
              }
              return py::make_tuple(target, merged, count);
          },
          py::arg("positions"), py::arg("submesh_of_vertex"), py::arg("submesh_count"), py::arg("chosen"),
          py::arg("distance"), py::arg("threads") = 0,
          "(target int32 per vertex, merged positions float32 (N, 3), vertices merged away).");

    m.def("weld_topology",
          [](const py::object& positions, const py::object& edges, const py::object& face_starts,
             const py::object& face_sizes, const py::object& corner_verts, const py::object& target,
             const py::object& corner_edges) {
              MeshArrays mesh(positions, edges, face_starts, face_sizes, corner_verts);
              auto t = checked<int32_t>(target, "target", py::ssize_t(mesh.view.vertex_count), 0);
              py::array_t<int32_t> ce_in;
              if (!corner_edges.is_none())
                  ce_in = checked<int32_t>(corner_edges, "corner_edges", py::ssize_t(mesh.view.corner_count), 0);
              const int32_t* ce_ptr = corner_edges.is_none() ? nullptr : ce_in.data();
              const py::ssize_t nv = py::ssize_t(mesh.view.vertex_count), ne = py::ssize_t(mesh.view.edge_count),
                                nf = py::ssize_t(mesh.view.face_count), nc = py::ssize_t(mesh.view.corner_count);
              auto vs = empty<int32_t>(nv), es = empty<int32_t>(ne), fs = empty<int32_t>(nf), fst = empty<int32_t>(nf),
                   cs = empty<int32_t>(nc), cv = empty<int32_t>(nc), ce = empty<int32_t>(nc);
              auto e2 = empty<int32_t>(ne, 2);
              WeldOutput out{vs.mutable_data(), es.mutable_data(), e2.mutable_data(), fs.mutable_data(),
                             fst.mutable_data(), cs.mutable_data(), cv.mutable_data(), ce.mutable_data()};
              WeldCounts counts;
              {
                  py::gil_scoped_release release;
                  counts = weld_topology(mesh.view, ce_ptr, t.data(), out);
              }
              using py::slice;
              py::dict r;
              r["vertex_source"] = vs[slice(0, counts.vertices, 1)];
              r["edge_source"] = es[slice(0, counts.edges, 1)];
              r["edges"] = e2[slice(0, counts.edges, 1)];
              r["face_source"] = fs[slice(0, counts.faces, 1)];
              r["face_starts"] = fst[slice(0, counts.faces, 1)];
              r["corner_source"] = cs[slice(0, counts.corners, 1)];
              r["corner_verts"] = cv[slice(0, counts.corners, 1)];
              r["corner_edges"] = ce[slice(0, counts.corners, 1)];
              r["incomplete"] = counts.incomplete;
              return r;
          },
          py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"),
          py::arg("corner_verts"), py::arg("target"), py::arg("corner_edges") = py::none(),
          "The mesh after merging each vertex into target[v], as Blender's weld leaves it (see boxmarch.core.weld).");
}

// Pack UVs by height.
void bind_pack_uv(py::module_& m) {
    m.def("pack_uv_by_height", &pack_uv_py, py::arg("corner_uv"), py::arg("positions"), py::arg("edges"),
          py::arg("face_starts"), py::arg("face_sizes"), py::arg("corner_verts"), py::kw_only(),
          py::arg("face_mask"), py::arg("vertex_height"), py::arg("submesh_of_vertex"), py::arg("submesh_count"),
          py::arg("padding"), py::arg("max_per_row"), py::arg("lock_overlapping"),
          "Pack UV islands of the masked faces in rows by submesh height; corner_uv is written in place.");

    py::enum_<FrameSource>(m, "FrameSource")
        .value("FACES", FrameSource::Faces)
        .value("FACE_EDGE", FrameSource::FaceEdge)
        .value("EDGES", FrameSource::Edges)
        .value("ONE_AXIS", FrameSource::OneAxis)
        .value("IDENTITY", FrameSource::Identity);
    py::enum_<SubmeshStatus>(m, "SubmeshStatus")
        .value("BAKED", SubmeshStatus::Baked)
        .value("UNCHANGED", SubmeshStatus::Unchanged)
        .value("NOT_SELECTED", SubmeshStatus::NotSelected);
}

}  // namespace

PYBIND11_MODULE(_core, m) {
    m.doc() = "boxmarch native core: submeshes, frames, offset encoding (see boxmarch.core for the documented API)";

    bind_mesh(m);
    bind_bake(m);
    bind_raymarch(m);
    bind_selection_tools(m);
    bind_merge_tools(m);
    bind_pack_uv(m);
}
