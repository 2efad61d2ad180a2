// boxmarch._core: the bake and its corner expansion.
#include "arrays.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <cstring>

namespace boxmarch::bindings {

namespace {

#ifdef __GLIBC__
constexpr size_t kTrimAfterVertices = size_t(1) << 20;
#endif

py::dict bake_py(const py::object& positions, const py::object& edges, const py::object& face_starts,
                 const py::object& face_sizes, const py::object& corner_verts, const py::object& mask,
                 const py::object& previous_fingerprints, const py::object& offsets_out, double angle_epsilon,
                 const std::string& origin, bool sort_axes_by_extent, int axis_turn, const std::string& encoding,
                 bool use_cache, int threads, bool arrays_owned) {
    MeshArrays mesh(positions, edges, face_starts, face_sizes, corner_verts, arrays_owned);
    const py::ssize_t n = py::ssize_t(mesh.view.vertex_count);
    BakeOptions options;
    options.angle_epsilon = angle_epsilon;
    if (origin == "BOUNDS")
        options.origin = OriginMode::Bounds;
    else if (origin == "MEAN")
        options.origin = OriginMode::Mean;
    else
        throw py::value_error("origin must be 'BOUNDS' or 'MEAN', got '" + origin + "'");
    if (encoding == "FLOAT_COLOR")
        options.encoding = ColorEncoding::Float;
    else if (encoding == "BYTE_COLOR")
        options.encoding = ColorEncoding::Byte;
    else
        throw py::value_error("encoding must be 'FLOAT_COLOR' or 'BYTE_COLOR', got '" + encoding + "'");
    options.sort_axes_by_extent = sort_axes_by_extent;
    options.axis_turn = axis_turn;
    options.use_cache = use_cache;
    options.threads = threads;
    const bool bytes = options.encoding == ColorEncoding::Byte;

    py::array_t<uint8_t> mask_arr;
    py::array_t<uint32_t> previous;
    if (!mask.is_none()) mask_arr = input_or_own<uint8_t>(arrays_owned, mask, "mask", n, 0);
    if (!previous_fingerprints.is_none())
        previous = input_or_own<uint32_t>(arrays_owned, previous_fingerprints, "previous_fingerprints", n, 0);
    py::array offsets;
    if (offsets_out.is_none()) {
        offsets = bytes ? py::array(empty<uint8_t>(n, 4)) : py::array(empty<float>(n, 4));
        // Zeros where nothing is baked, as for the per-submesh arrays. Without a mask or previous
        // fingerprints every submesh is baked and every row is written.
        if (!mask.is_none() || !previous_fingerprints.is_none())
            std::memset(offsets.mutable_data(), 0, size_t(offsets.nbytes()));
    } else
        offsets = bytes ? py::array(checked<uint8_t>(offsets_out, "offsets", n, 4, true))
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
        if (bytes)
            out.offset_byte = static_cast<uint8_t*>(offsets.mutable_data());
        else
            out.offset_float = static_cast<float*>(offsets.mutable_data());
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

}  // namespace

// The bake and its corner expansion.
void bind_bake(py::module_& m) {
    m.def("bake", &bake_py, py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"),
          py::arg("corner_verts"), py::kw_only(), py::arg("mask") = py::none(),
          py::arg("previous_fingerprints") = py::none(), py::arg("offsets") = py::none(),
          py::arg("angle_epsilon") = BakeOptions{}.angle_epsilon, py::arg("origin") = "BOUNDS",
          py::arg("sort_axes_by_extent") = false, py::arg("axis_turn") = 0, py::arg("encoding") = "FLOAT_COLOR",
          py::arg("use_cache") = true, py::arg("threads") = 0, py::arg("arrays_owned") = false,
          "Bake every submesh; see boxmarch.core.bake.");

    m.def(
            "expand_corner_quaternions",
            [](const py::object& corner_uv, int half, const py::object& corner_verts,
               const py::object& submesh_of_vertex, const py::object& quaternions, const py::object& write_submesh) {
                auto cv = input<int32_t>(corner_verts, "corner_verts", -1, 0);
                auto uv = checked<float>(corner_uv, "corner_uv", cv.shape(0), 2, true);
                auto sv = input<int32_t>(submesh_of_vertex, "submesh_of_vertex", -1, 0);
                auto q = input<float>(quaternions, "quaternions", -1, 4);
                py::array_t<uint8_t> w;
                if (!write_submesh.is_none()) w = input<uint8_t>(write_submesh, "write_submesh", q.shape(0), 0);
                const uint8_t* wp = write_submesh.is_none() ? nullptr : w.data();
                float* out = uv.mutable_data();
                py::gil_scoped_release release;
                expand_corner_quaternions(out, half, cv.data(), size_t(cv.shape(0)), sv.data(), size_t(sv.shape(0)),
                                          q.data(), size_t(q.shape(0)), wp);
            },
            py::arg("corner_uv"), py::arg("half"), py::arg("corner_verts"), py::arg("submesh_of_vertex"),
            py::arg("quaternions"), py::arg("write_submesh") = py::none(),
            "Fill corner_uv (float32[C, 2]) in place with each corner's (q.x, q.y) (half=0) or (q.z, q.w) (half=1).");

    m.def(
            "axis_turn_matrices",
            []() {
                py::array_t<double> all({24, 3, 3});
                double* d = all.mutable_data();
                for (int i = 0; i < 24; ++i) {
                    double col_major[9];
                    axis_turn_matrix(col_major, i);
                    for (int r = 0; r < 3; ++r)
                        for (int c = 0; c < 3; ++c) d[i * 9 + r * 3 + c] = col_major[c * 3 + r];
                }
                return all;
            },
            "The 24 axis-aligned turns as row-major 3x3 matrices; column i is the new local axis i in the derived "
            "frame.");
}

}  // namespace boxmarch::bindings
