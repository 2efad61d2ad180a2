// boxmarch._core: NumPy arrays in and out of the native core, without copies. This file registers
// the bind_* groups (bindings/bind_*.cpp, sharing bindings/arrays.h) and binds the mesh checks.
#include "arrays.h"

namespace boxmarch::bindings {

// Mesh checks and submeshes.
void bind_mesh(py::module_& m) {
    m.def(
            "validate_mesh",
            [](const py::object& p, const py::object& e, const py::object& fs, const py::object& fz,
               const py::object& cv) { MeshArrays mesh(p, e, fs, fz, cv); },
            py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"),
            py::arg("corner_verts"), "Raise ValueError naming the first malformed element of the mesh arrays.");

    m.def(
            "find_submeshes",
            [](const py::object& p, const py::object& e, const py::object& fs, const py::object& fz,
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
            py::arg("positions"), py::arg("edges"), py::arg("face_starts"), py::arg("face_sizes"),
            py::arg("corner_verts"),
            "Connected components: (submesh_of_vertex int32[N], count), numbered by lowest vertex.");

    m.def(
            "face_starts_from_corner_edges",
            [](const py::object& corner_verts, const py::object& corner_edges, const py::object& edges,
               size_t vertex_count, bool arrays_owned) {
                auto cv = input_or_own<int32_t>(arrays_owned, corner_verts, "corner_verts", -1, 0);
                auto ce = input_or_own<int32_t>(arrays_owned, corner_edges, "corner_edges", cv.shape(0), 0);
                auto e = input_or_own<int32_t>(arrays_owned, edges, "edges", -1, 2);
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
            py::arg("arrays_owned") = false,
            "(face_starts int32, count): face boundaries recovered from corner edges; compare count with the real face "
            "count.");
}

}  // namespace boxmarch::bindings

PYBIND11_MODULE(_core, m) {
    using namespace boxmarch::bindings;
    m.doc() = "boxmarch native core: submeshes, frames, offset encoding (see boxmarch.core for the documented API)";

    m.attr("ANGLE_EPSILON_MIN") = boxmarch::kAngleEpsilonMin;
    m.attr("ANGLE_EPSILON_MAX") = boxmarch::kAngleEpsilonMax;
    m.attr("ANGLE_EPSILON_DEFAULT") = boxmarch::BakeOptions{}.angle_epsilon;
    bind_mesh(m);
    bind_bake(m);
    bind_raymarch(m);
    bind_selection_tools(m);
    bind_merge_tools(m);
    bind_pack_uv(m);
    bind_box_params(m);
}
