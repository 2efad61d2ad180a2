// What the bind_*.cpp files of boxmarch._core share: array checks and conversions (this code
// only checks arrays and moves them; every algorithm lives in cpp/), and the bind_* functions
// module.cpp registers.
#pragma once

#include "boxmarch/boxmarch.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace boxmarch::bindings {

namespace py = pybind11;

template <class T>
const char* dtype_name();
template <>
inline const char* dtype_name<float>() {
    return "float32";
}
template <>
inline const char* dtype_name<double>() {
    return "float64";
}
template <>
inline const char* dtype_name<int32_t>() {
    return "int32";
}
template <>
inline const char* dtype_name<uint32_t>() {
    return "uint32";
}
template <>
inline const char* dtype_name<uint8_t>() {
    return "uint8";
}

inline std::string shape_of(const py::array& a) {
    std::ostringstream s;
    s << "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
    s << (a.ndim() == 1 ? ",)" : ")");
    return s.str();
}

// The array as a C-contiguous T array of shape (rows, cols) (cols 0: one dimension), or a
// ValueError saying what was expected and what came. rows < 0 accepts any row count.
template <class T>
py::array_t<T> checked(const py::object& obj, const char* name, py::ssize_t rows, py::ssize_t cols,
                       bool writable = false) {
    if (!py::isinstance<py::array>(obj)) throw py::value_error(std::string(name) + " must be a NumPy array");
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

// checked(), then a private copy: the array the core reads with the GIL released. Another Python
// thread may write the caller's array at any moment of the call (NumPy also releases the GIL
// inside its own loops, so holding it would not stop a write already running): the core's checks
// of indices and finiteness must see exactly what it then reads, so both read the copy.
template <class T>
py::array_t<T> input(const py::object& obj, const char* name, py::ssize_t rows, py::ssize_t cols) {
    const py::array_t<T> a = checked<T>(obj, name, rows, cols);
    py::array_t<T> copy(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
    std::memcpy(copy.mutable_data(), a.data(), size_t(a.nbytes()));
    return copy;
}

// input(), or the checked array itself where the caller vouches that nothing else holds it (it
// made the array for this call): no thread can write what no other code can reach.
template <class T>
py::array_t<T> input_or_own(bool own, const py::object& obj, const char* name, py::ssize_t rows, py::ssize_t cols) {
    return own ? checked<T>(obj, name, rows, cols) : input<T>(obj, name, rows, cols);
}

// Arrays of one mesh (private copies, see input(), unless `own`), kept alive while the view
// points into them.
struct MeshArrays {
    py::array_t<float> positions;
    py::array_t<int32_t> edges, face_starts, face_sizes, corner_verts;
    MeshView view;

    MeshArrays(const py::object& p, const py::object& e, const py::object& fs, const py::object& fz,
               const py::object& cv, bool own = false)
            : positions(input_or_own<float>(own, p, "positions", -1, 3)),
              edges(input_or_own<int32_t>(own, e, "edges", -1, 2)),
              face_starts(input_or_own<int32_t>(own, fs, "face_starts", -1, 0)),
              face_sizes(input_or_own<int32_t>(own, fz, "face_sizes", face_starts.shape(0), 0)),
              corner_verts(input_or_own<int32_t>(own, cv, "corner_verts", -1, 0)) {
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

// submesh_of_vertex as int32[vertex_count] (a private copy); the core checks the ids' range.
inline py::array_t<int32_t> checked_submeshes(const py::object& obj, py::ssize_t vertex_count) {
    return input<int32_t>(obj, "submesh_of_vertex", vertex_count, 0);
}

void bind_mesh(py::module_& m);
void bind_bake(py::module_& m);
void bind_raymarch(py::module_& m);
void bind_selection_tools(py::module_& m);
void bind_merge_tools(py::module_& m);
void bind_pack_uv(py::module_& m);
void bind_box_params(py::module_& m);

}  // namespace boxmarch::bindings
