// boxmarch._core: per-box parameters, the box hierarchy and the nearest points it builds on.
// Every array the core reads with the GIL released is a private copy (input()).
#include "arrays.h"

namespace boxmarch::bindings {

void bind_box_params(py::module_& m) {
    m.def(
            "reduce_per_submesh",
            [](const py::object& values, const py::object& submesh_of_element, size_t submesh_count) {
                if (!py::isinstance<py::array>(values) || py::array(values).ndim() != 2)
                    throw py::value_error("values must be a 2-D float32 array (elements, components)");
                auto v = input<float>(values, "values", -1, py::array(values).shape(1));
                auto ids = input<int32_t>(submesh_of_element, "submesh_of_element", v.shape(0), 0);
                const size_t components = size_t(v.shape(1));
                py::array_t<float> out = empty<float>(py::ssize_t(submesh_count), py::ssize_t(components));
                py::array_t<uint8_t> disagrees = empty<uint8_t>(py::ssize_t(submesh_count));
                size_t count;
                {
                    py::gil_scoped_release release;
                    count = reduce_per_submesh(out.mutable_data(), disagrees.mutable_data(), v.data(),
                                               size_t(v.shape(0)), components, ids.data(), submesh_count);
                }
                return py::make_tuple(out, disagrees, count);
            },
            py::arg("values"), py::arg("submesh_of_element"), py::arg("submesh_count"),
            "(values float32[S, k], disagrees uint8[S], count): the value most elements of each submesh hold.");

    m.def(
            "box_random",
            [](const py::object& fingerprints, uint32_t seed) {
                auto fp = checked<uint32_t>(fingerprints, "fingerprints", -1, 0);  // read holding the GIL
                py::array_t<float> out = empty<float>(fp.shape(0));
                box_random(out.mutable_data(), fp.data(), size_t(fp.shape(0)), seed);
                return out;
            },
            py::arg("fingerprints"), py::arg("seed"), "float32[S] in [0, 1) from each box's fingerprint and a seed.");

    m.def(
            "box_hierarchy",
            [](const py::object& origins, const py::object& quaternions, const py::object& half_extents, int rule,
               const py::object& given_parent) {
                auto o = input<double>(origins, "origins", -1, 3);
                const py::ssize_t n = o.shape(0);
                auto q = input<float>(quaternions, "quaternions", n, 4);
                auto h = input<double>(half_extents, "half_extents", n, 3);
                py::array_t<int32_t> given;
                if (!given_parent.is_none()) given = input<int32_t>(given_parent, "given_parent", n, 0);
                const int32_t* gp = given_parent.is_none() ? nullptr : given.data();
                py::array_t<int32_t> parent = empty<int32_t>(n), depth = empty<int32_t>(n);
                int32_t deepest;
                {
                    py::gil_scoped_release release;
                    deepest = box_hierarchy(parent.mutable_data(), depth.mutable_data(), o.data(), q.data(), h.data(),
                                            size_t(n), HierarchyRule(rule), gp);
                }
                return py::make_tuple(parent, depth, deepest);
            },
            py::arg("origins"), py::arg("quaternions"), py::arg("half_extents"), py::arg("rule"),
            py::arg("given_parent") = py::none(),
            "(parent int32[S], depth int32[S], deepest): see boxmarch.core.box_hierarchy.");

    m.def(
            "nearest_points",
            [](const py::object& points, const py::object& candidates, int threads) {
                auto p = input<double>(points, "points", -1, 3);
                auto c = input<double>(candidates, "candidates", -1, 3);
                py::array_t<int64_t> out = empty<int64_t>(p.shape(0));
                {
                    py::gil_scoped_release release;
                    nearest_points(out.mutable_data(), p.data(), size_t(p.shape(0)), c.data(), size_t(c.shape(0)),
                                   threads);
                }
                return out;
            },
            py::arg("points"), py::arg("candidates"), py::arg("threads") = 0,
            "int64[N]: the row of candidates nearest each point (-1: none); see boxmarch.core.nearest_rows.");
}

}  // namespace boxmarch::bindings
