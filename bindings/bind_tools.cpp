// boxmarch._core: the submesh tools (close pairs, selection, dedup, merge, weld, UV packing).
#include "arrays.h"

#include <algorithm>
#include <vector>

namespace boxmarch::bindings {

namespace {

py::array_t<uint32_t> close_pairs_py(const py::object& positions, double radius, const py::object& groups,
                                     const std::string& method, int threads) {
    auto p = input<float>(positions, "positions", -1, 3);
    const size_t n = size_t(p.shape(0));
    py::array_t<int32_t> g;
    if (!groups.is_none()) g = input<int32_t>(groups, "groups", p.shape(0), 0);
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
    // corner_uv is read and written: the core works on a private copy (see input()), copied back.
    auto uv_out = checked<float>(corner_uv, "corner_uv", py::ssize_t(mesh.view.corner_count), 2, true);
    auto uv = input<float>(corner_uv, "corner_uv", py::ssize_t(mesh.view.corner_count), 2);
    const py::ssize_t n = py::ssize_t(mesh.view.vertex_count);
    auto height = input<float>(vertex_height, "vertex_height", n, 0);
    auto ids = checked_submeshes(submesh_of_vertex, n);
    py::array_t<uint8_t> mask;
    if (!face_mask.is_none()) mask = input<uint8_t>(face_mask, "face_mask", py::ssize_t(mesh.view.face_count), 0);
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
    std::memcpy(uv_out.mutable_data(), uv.data(), size_t(uv.nbytes()));
    py::dict r;
    r["islands"] = report.islands;
    r["groups"] = report.groups;
    r["rows"] = report.rows;
    r["scale"] = report.scale;
    return r;
}

}  // namespace

// Close pairs, the two selection tools and dedup.
void bind_selection_tools(py::module_& m) {
    m.def("find_close_pairs", &close_pairs_py, py::arg("positions"), py::arg("radius"), py::kw_only(),
          py::arg("groups") = py::none(), py::arg("method") = "HASH", py::arg("threads") = 0,
          "uint32 (P, 2): every pair i < j within radius (inclusive), sorted; see boxmarch.core.find_close_pairs.");

    m.def(
            "select_linked_submeshes",
            [](const py::object& selected, const py::object& submesh_of_vertex, size_t submesh_count) {
                auto sel = input<uint8_t>(selected, "selected", -1, 0);
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

    m.def(
            "select_linked_across",
            [](const py::object& positions, const py::object& selected, const py::object& submesh_of_vertex,
               size_t submesh_count, double epsilon, int threads) {
                auto p = input<float>(positions, "positions", -1, 3);
                auto sel = input<uint8_t>(selected, "selected", p.shape(0), 0);
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

    m.def(
            "find_duplicate_submeshes",
            [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
               const py::object& candidate, double tolerance, int threads) {
                auto p = input<float>(positions, "positions", -1, 3);
                auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
                py::array_t<uint8_t> cand;
                if (!candidate.is_none()) cand = input<uint8_t>(candidate, "candidate", py::ssize_t(submesh_count), 0);
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
    m.def(
            "merge_passes",
            [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
               const py::object& chosen, double distance, int threads) {
                auto p = input<float>(positions, "positions", -1, 3);
                auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
                auto ch = input<uint8_t>(chosen, "chosen", py::ssize_t(submesh_count), 0);
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

    m.def(
            "merge_targets",
            [](const py::object& positions, const py::object& submesh_of_vertex, size_t submesh_count,
               const py::object& chosen, double distance, int threads) {
                auto p = input<float>(positions, "positions", -1, 3);
                auto ids = checked_submeshes(submesh_of_vertex, p.shape(0));
                auto ch = input<uint8_t>(chosen, "chosen", py::ssize_t(submesh_count), 0);
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

    m.def(
            "weld_topology",
            [](const py::object& positions, const py::object& edges, const py::object& face_starts,
               const py::object& face_sizes, const py::object& corner_verts, const py::object& target,
               const py::object& corner_edges) {
                MeshArrays mesh(positions, edges, face_starts, face_sizes, corner_verts);
                auto t = input<int32_t>(target, "target", py::ssize_t(mesh.view.vertex_count), 0);
                py::array_t<int32_t> ce_in;
                if (!corner_edges.is_none())
                    ce_in = input<int32_t>(corner_edges, "corner_edges", py::ssize_t(mesh.view.corner_count), 0);
                const int32_t* ce_ptr = corner_edges.is_none() ? nullptr : ce_in.data();
                const py::ssize_t nv = py::ssize_t(mesh.view.vertex_count), ne = py::ssize_t(mesh.view.edge_count),
                                  nf = py::ssize_t(mesh.view.face_count), nc = py::ssize_t(mesh.view.corner_count);
                auto vs = empty<int32_t>(nv), es = empty<int32_t>(ne), fs = empty<int32_t>(nf),
                     fst = empty<int32_t>(nf), cs = empty<int32_t>(nc), cv = empty<int32_t>(nc),
                     ce = empty<int32_t>(nc);
                auto e2 = empty<int32_t>(ne, 2);
                WeldOutput out{vs.mutable_data(),  es.mutable_data(), e2.mutable_data(), fs.mutable_data(),
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
          py::arg("face_starts"), py::arg("face_sizes"), py::arg("corner_verts"), py::kw_only(), py::arg("face_mask"),
          py::arg("vertex_height"), py::arg("submesh_of_vertex"), py::arg("submesh_count"), py::arg("padding"),
          py::arg("max_per_row"), py::arg("lock_overlapping"),
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

}  // namespace boxmarch::bindings
