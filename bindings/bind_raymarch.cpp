// boxmarch._core: the CPU reference raymarcher and renderer.
#include "arrays.h"

#include <cmath>
#include <cstring>
#include <vector>

namespace boxmarch::bindings {

namespace {

SdfPreset preset_of(int sdf) {
    if (sdf < 0 || sdf >= kSdfPresetCount)
        throw py::value_error("sdf must be a preset index 0.." + std::to_string(kSdfPresetCount - 1) + ", got " +
                              std::to_string(sdf));
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

py::dict raymarch_py(const py::object& origins, const py::object& directions, const py::object& half_extents, int sdf,
                     int max_steps, float epsilon, float relaxation, float max_distance, int threads) {
    auto ro = input<float>(origins, "origins", -1, 3);
    auto rd = input<float>(directions, "directions", ro.shape(0), 3);
    auto h = input<float>(half_extents, "half_extents", ro.shape(0), 3);
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
}

// The caller's images of a render_boxes call, checked, and the private copies of those the core
// also reads (depth for the depth test, steps for the sums), written back by copy_back(). normals
// and steps are optional (a default array_t is an empty array, not None: the flags say).
struct FrameImages {
    py::ssize_t height = 0, width = 0;
    py::array_t<float> rgba, depth_out, depth, normals;
    py::array_t<int32_t> steps_out, steps;
    bool has_normals = false, has_steps = false;

    RenderImages images() {
        RenderImages images;
        images.rgba = rgba.mutable_data();
        images.depth = depth.mutable_data();
        images.normals = has_normals ? normals.mutable_data() : nullptr;
        images.steps = has_steps ? steps.mutable_data() : nullptr;
        return images;
    }

    void copy_back() {
        std::memcpy(depth_out.mutable_data(), depth.data(), size_t(depth.nbytes()));
        if (has_steps) std::memcpy(steps_out.mutable_data(), steps.data(), size_t(steps.nbytes()));
    }
};

FrameImages frame_images(const py::object& rgba, const py::object& depth, const py::object& normals,
                         const py::object& steps) {
    if (!py::isinstance<py::array>(depth) || py::reinterpret_borrow<py::array>(depth).ndim() != 2)
        throw py::value_error("depth must be a float32 array of shape (height, width)");
    FrameImages f;
    f.height = py::reinterpret_borrow<py::array>(depth).shape(0);
    f.width = py::reinterpret_borrow<py::array>(depth).shape(1);
    f.depth_out = checked<float>(depth, "depth", f.height, f.width, true);
    f.depth = input<float>(depth, "depth", f.height, f.width);
    f.rgba = checked<float>(rgba, "rgba", f.height * f.width, 4, true);
    f.has_normals = !normals.is_none();
    f.has_steps = !steps.is_none();
    if (f.has_normals) f.normals = checked<float>(normals, "normals", f.height * f.width, 3, true);
    if (f.has_steps) {
        f.steps_out = checked<int32_t>(steps, "steps", f.height * f.width, 0, true);
        f.steps = input<int32_t>(steps, "steps", f.height * f.width, 0);
    }
    return f;
}

// RenderCost as the dict boxmarch.core.render_boxes returns.
py::dict cost_counts(const RenderCost& cost) {
    py::dict counts;
    counts["fragments"] = cost.fragments;
    counts["marched_fragments"] = cost.marched_fragments;
    counts["occluded_fragments"] = cost.occluded_fragments;
    counts["lod_fragments"] = cost.lod_fragments;
    counts["sdf_evaluations"] = cost.sdf_evaluations;
    counts["hidden_fragments"] = cost.hidden_fragments;
    counts["hidden_evaluations"] = cost.hidden_evaluations;
    counts["covered_pixels"] = cost.covered_pixels;
    return counts;
}

py::dict render_boxes_py(const py::object& origins, const py::object& quaternions, const py::object& half_extents,
                         const py::object& object_to_clip, const py::object& object_to_view,
                         const py::object& base_color, const py::object& rgba, const py::object& depth,
                         const py::object& normals, const py::object& steps, int sdf, int max_steps, float epsilon,
                         float relaxation, float max_distance, int threads, const py::object& order, bool early_depth,
                         float quality, int normal, bool occluders) {
    auto c = input<float>(origins, "origins", -1, 3);
    auto q = input<float>(quaternions, "quaternions", c.shape(0), 4);
    auto h = input<float>(half_extents, "half_extents", c.shape(0), 3);
    auto color = input<float>(base_color, "base_color", 3, 0);
    FrameImages frame = frame_images(rgba, depth, normals, steps);
    std::vector<float> clip = column_major(object_to_clip, "object_to_clip");
    std::vector<float> view_m = column_major(object_to_view, "object_to_view");
    MarchOptions o = march_options(sdf, max_steps, epsilon, relaxation, max_distance, threads);
    RenderView view;
    view.object_to_clip = clip.data();
    view.object_to_view = view_m.data();
    view.width = uint32_t(frame.width);
    view.height = uint32_t(frame.height);
    for (int k = 0; k < 3; ++k) view.base_color[k] = color.data()[k];
    RenderImages images = frame.images();
    py::array_t<uint32_t> draw_order;
    RenderCost cost;
    RenderPlan plan;
    if (!order.is_none()) {
        draw_order = input<uint32_t>(order, "order", c.shape(0), 0);
        plan.order = draw_order.data();
    }
    plan.early_depth = early_depth;
    plan.occluders = occluders;
    plan.quality = quality;
    plan.normal = NormalRule(normal);
    plan.cost = &cost;
    {
        py::gil_scoped_release release;
        render_boxes(c.data(), q.data(), h.data(), size_t(c.shape(0)), view, o, images, plan);
    }
    frame.copy_back();
    return cost_counts(cost);
}

py::array_t<float> sdf_distance_py(int sdf, const py::object& points, const py::object& half_extents) {
    auto p = checked<float>(points, "points", -1, 3);  // read holding the GIL
    auto h = checked<float>(half_extents, "half_extents", p.shape(0), 3);
    const SdfPreset preset = preset_of(sdf);
    py::array_t<float> d = empty<float>(p.shape(0));
    for (py::ssize_t i = 0; i < p.shape(0); ++i)
        d.mutable_data()[i] = sdf_distance(preset, p.data() + 3 * i, h.data() + 3 * i);
    return d;
}

py::tuple occluder_boxes_py(int sdf, const py::object& half_extents) {
    auto h = checked<float>(half_extents, "half_extents", -1, 3);
    const SdfPreset preset = preset_of(sdf);
    const py::ssize_t n = h.shape(0);
    py::array_t<float> centres({n, py::ssize_t(kMaxOccluders), py::ssize_t(3)});
    py::array_t<float> halves({n, py::ssize_t(kMaxOccluders), py::ssize_t(3)});
    for (py::ssize_t i = 0; i < n; ++i)
        for (int k = 0; k < kMaxOccluders; ++k)
            occluder_box(preset, h.data() + 3 * i, k, centres.mutable_data() + (i * kMaxOccluders + k) * 3,
                         halves.mutable_data() + (i * kMaxOccluders + k) * 3);
    return py::make_tuple(centres, halves);
}

}  // namespace

// The CPU reference raymarcher and renderer.
void bind_raymarch(py::module_& m) {
    m.def("raymarch", &raymarch_py, py::arg("origins"), py::arg("directions"), py::arg("half_extents"), py::kw_only(),
          py::arg("sdf"), py::arg("max_steps"), py::arg("epsilon"), py::arg("relaxation"), py::arg("max_distance"),
          py::arg("threads") = 0, "Sphere-trace box-local rays; see boxmarch.core.raymarch.");
    m.def("render_boxes", &render_boxes_py, py::arg("origins"), py::arg("quaternions"), py::arg("half_extents"),
          py::arg("object_to_clip"), py::arg("object_to_view"), py::arg("base_color"), py::arg("rgba"),
          py::arg("depth"), py::arg("normals"), py::arg("steps"), py::kw_only(), py::arg("sdf"), py::arg("max_steps"),
          py::arg("epsilon"), py::arg("relaxation"), py::arg("max_distance"), py::arg("threads") = 0,
          py::arg("order") = py::none(), py::arg("early_depth") = false, py::arg("quality") = 1.0f,
          py::arg("normal") = 0, py::arg("occluders") = false,
          "Raymarch boxes into caller-owned images (rgba (H*W, 4), depth (H, W), normals (H*W, 3), steps (H*W,)) "
          "in draw order `order` (None: as given); returns the frame's cost counts (RenderCost); "
          "see boxmarch.core.render_boxes.");
    m.def("sdf_distance", &sdf_distance_py, py::arg("sdf"), py::arg("points"), py::arg("half_extents"),
          "Distances of box-local points to a preset.");
    m.def("occluder_boxes", &occluder_boxes_py, py::arg("sdf"), py::arg("half_extents"),
          "The conservative occluder boxes of a preset per box: (centres, half-extents), each (N, 4, 3).");
}

}  // namespace boxmarch::bindings
