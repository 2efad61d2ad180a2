// The CPU reference raymarcher, in float like the GPU, so the viewport preview can be tested
// against it pixel by pixel. The SDF library, the slab test, the normal tap and the light are
// shaders/glsl's own, translated by shaders/generate.py (shader_library.h); the march and the
// normal, which call map() in GLSL, are written here around the preset switch, statement for
// statement as raymarch.glsl has them. The march is sphere tracing (Hart 1996, steps of the
// distance bound, here scaled by `relaxation`); the box entry is the slab test (Kay and Kajiya 1986).
#include "boxmarch/boxmarch.h"
#include "internal.h"
#include "shader_library.h"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {
namespace {

using glm::vec2;
using glm::vec3;
using glm::vec4;

void check_options(const MarchOptions& o) {
    if (o.max_steps < 0) throw std::invalid_argument("max_steps must be >= 0, got " + std::to_string(o.max_steps));
    if (!(o.epsilon > 0.0f)) throw std::invalid_argument("epsilon must be > 0, got " + std::to_string(o.epsilon));
    if (!(o.relaxation > 0.0f && o.relaxation <= 2.0f))
        throw std::invalid_argument("relaxation must be in (0, 2], got " + std::to_string(o.relaxation));
    if (!(o.max_distance > 0.0f))
        throw std::invalid_argument("max_distance must be > 0, got " + std::to_string(o.max_distance));
    if (int(o.sdf) < 0 || int(o.sdf) >= kSdfPresetCount)
        throw std::invalid_argument("unknown SDF preset " + std::to_string(int(o.sdf)));
}

// The map() of a preset: sdf.glsl's sdf_preset_* for the box's half-extents h.
float sdf_preset(SdfPreset kind, vec3 p, vec3 h) {
    switch (kind) {
        case SdfPreset::Box:
            return shader::sdf_preset_box(p, h);
        case SdfPreset::Sphere:
            return shader::sdf_preset_sphere(p, h);
        case SdfPreset::RoundedBox:
            return shader::sdf_preset_rounded_box(p, h);
        case SdfPreset::Capsule:
            return shader::sdf_preset_capsule(p, h);
        case SdfPreset::Cylinder:
            return shader::sdf_preset_cylinder(p, h);
        case SdfPreset::Torus:
            return shader::sdf_preset_torus(p, h);
        case SdfPreset::Link:
            return shader::sdf_preset_link(p, h);
    }
    return shader::sdf_preset_box(p, h);
}

struct March {
    bool hit;
    float t;
    int steps;
    float d;  // the last map() value (bm_normal's d)
};

// raymarch.glsl: bm_march, without its 512-step bound (a GLSL ES 1.00 constant loop limit):
// secant steps under secant.x (at most secant.y times the distance; secant.x = 0: none); a step
// under 2^-23 t ends it as a hit.
March bm_march(SdfPreset kind, vec3 ro, vec3 rd, vec3 h, float t_end, const MarchOptions& o, vec2 secant) {
    float t = 0.0f, d = 0.0f, last_d = 0.0f, last_advance = 0.0f;
    for (int i = 0; i < o.max_steps; ++i) {
        d = sdf_preset(kind, ro + rd * t, h);
        if (d < o.epsilon) return {true, t, i + 1, d};
        float advance = o.relaxation * d;
        if (d < secant.x && d < last_d) advance = std::min(d * last_advance / (last_d - d), secant.y * d);
        if (advance < 1.2e-7f * t) return {true, t, i + 1, d};  // a step t cannot take: a hit
        last_d = d;
        last_advance = advance;
        t += advance;
        if (t > t_end) return {false, t, i + 1, d};
    }
    return {false, t, o.max_steps, d};
}

// raymarch.glsl: bm_one_tap (one map() where the ray passes nearest the box's centre).
March bm_one_tap(SdfPreset kind, vec3 ro, vec3 rd, vec3 h, float t_end, float footprint) {
    const float t = std::clamp(-glm::dot(ro, rd), 0.0f, t_end);
    const float d = sdf_preset(kind, ro + rd * t, h);
    return {d < 0.5f * footprint, t, 1, d};
}

vec3 unit_or_zero(vec3 n) {
    const float len = glm::length(n);
    return len > 0.0f ? n / len : vec3(0.0f);
}

// raymarch.glsl: bm_normal (forward differences from d = map(p)).
vec3 bm_normal(SdfPreset kind, vec3 p, vec3 h, float d, float e) {
    return unit_or_zero(vec3(sdf_preset(kind, p + vec3(e, 0.0f, 0.0f), h), sdf_preset(kind, p + vec3(0.0f, e, 0.0f), h),
                             sdf_preset(kind, p + vec3(0.0f, 0.0f, e), h)) -
                        d);
}

// The normal of a hit at p (map(p) = d) by `rule`, and its map() calls (NormalRule).
struct Normal {
    vec3 n;
    int evaluations;
};
Normal normal_by_rule(NormalRule rule, SdfPreset kind, vec3 p, vec3 h, float d, float epsilon) {
    const float e = shader::bm_normal_tap(h);
    if (rule == NormalRule::Forward) return {bm_normal(kind, p, h, d, e), 3};
    if (rule == NormalRule::Central) {
        vec3 n;
        for (int k = 0; k < 3; ++k) {
            vec3 step(0.0f);
            step[k] = e;
            n[k] = sdf_preset(kind, p + step, h) - sdf_preset(kind, p - step, h);
        }
        return {unit_or_zero(n), 6};
    }
    const float tap = std::max(epsilon, 1e-3f * shader::bm_max3(h));
    const vec3 a(1.0f, -1.0f, -1.0f), b(-1.0f, -1.0f, 1.0f), c(-1.0f, 1.0f, -1.0f), one(1.0f);
    return {unit_or_zero(a * sdf_preset(kind, p + a * tap, h) + b * sdf_preset(kind, p + b * tap, h) +
                         c * sdf_preset(kind, p + c * tap, h) + one * sdf_preset(kind, p + one * tap, h)),
            4};
}

void check_plan(const RenderPlan& plan, size_t box_count) {
    if (!(plan.quality > 0.0f && plan.quality <= 1.0f))
        throw std::invalid_argument("quality must be in (0, 1], got " + std::to_string(plan.quality));
    if (int(plan.normal) < 0 || int(plan.normal) >= kNormalRuleCount)
        throw std::invalid_argument("unknown normal rule " + std::to_string(int(plan.normal)));
    if (!plan.order) return;
    std::vector<uint8_t> seen(box_count, 0);
    for (size_t k = 0; k < box_count; ++k) {
        const uint32_t b = plan.order[k];
        if (b >= box_count || seen[b])
            throw std::invalid_argument("order must list every box index 0.." + std::to_string(box_count) +
                                        " - 1 once; entry " + std::to_string(k) + " is " + std::to_string(b));
        seen[b] = 1;
    }
}

// The pixel rectangle of every box (x0, y0, x1, y1 inclusive, rows from the top): the rasteriser's
// coverage, conservatively; the slab test per pixel decides exactly.
std::vector<glm::ivec4> pixel_rects(const float* origins, const float* quaternions, const float* half_extents,
                                    size_t box_count, const glm::mat4& to_clip, int W, int H) {
    std::vector<glm::ivec4> rects(box_count);
    for (size_t b = 0; b < box_count; ++b) {
        const glm::quat q(quaternions[4 * b + 3], quaternions[4 * b], quaternions[4 * b + 1], quaternions[4 * b + 2]);
        const vec3 c = glm::make_vec3(origins + 3 * b), h = glm::make_vec3(half_extents + 3 * b);
        // Clip the box against the near plane (z + w >= 0 in GL clip space): the pixel rectangle
        // of what lies in front is the box of the front corners and the edge crossings.
        vec4 clip[8];
        float front[8];
        for (int k = 0; k < 8; ++k) {
            vec3 corner(k & 1 ? h.x : -h.x, k & 2 ? h.y : -h.y, k & 4 ? h.z : -h.z);
            clip[k] = to_clip * vec4(c + q * corner, 1.0f);
            front[k] = clip[k].z + clip[k].w;
        }
        float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
        auto include = [&](vec4 p) {
            float sx = (p.x / p.w * 0.5f + 0.5f) * float(W);
            float sy = (0.5f - p.y / p.w * 0.5f) * float(H);
            x0 = std::min(x0, sx);
            x1 = std::max(x1, sx);
            y0 = std::min(y0, sy);
            y1 = std::max(y1, sy);
        };
        for (int k = 0; k < 8; ++k) {
            if (front[k] >= 0.0f) include(clip[k]);
            for (int bit = 1; bit < 8; bit <<= 1) {  // the three edges from k to k | bit
                const int l = k | bit;
                if (l == k || (front[k] >= 0.0f) == (front[l] >= 0.0f)) continue;
                include(clip[k] + (clip[l] - clip[k]) * (front[k] / (front[k] - front[l])));
            }
        }
        // first and last pixel centre inside [lo, hi], clamped before the cast (far-off boxes)
        auto first = [](float lo, int n) { return int(std::ceil(std::clamp(lo - 0.5f, -1.0f, float(n)))); };
        auto last = [](float hi, int n) { return int(std::floor(std::clamp(hi - 0.5f, -1.0f, float(n)))); };
        if (!(x0 <= x1 && y0 <= y1))
            rects[b] = glm::ivec4(0, 0, -1, -1);  // wholly behind the near plane
        else
            rects[b] = glm::ivec4(std::max(first(x0, W) - 1, 0), std::max(first(y0, H) - 1, 0),
                                  std::min(last(x1, W) + 1, W - 1), std::min(last(y1, H) + 1, H - 1));
    }
    return rects;
}

// The counts of one band of rows, added to the frame's: shown[pixel] = map() calls of the fragment
// the pixel shows (-1: none), covered[pixel] = inside some silhouette.
void add_band_cost(RenderCost& band, const std::vector<int32_t>& shown, const std::vector<uint8_t>& covered,
                   RenderCost& frame, std::mutex& lock) {
    uint64_t shown_fragments = 0, shown_evaluations = 0;
    for (size_t i = 0; i < shown.size(); ++i) {
        band.covered_pixels += covered[i];
        if (shown[i] >= 0) ++shown_fragments, shown_evaluations += uint64_t(shown[i]);
    }
    band.hidden_fragments = band.marched_fragments - shown_fragments;
    band.hidden_evaluations = band.sdf_evaluations - shown_evaluations;
    std::lock_guard<std::mutex> guard(lock);
    frame.fragments += band.fragments;
    frame.marched_fragments += band.marched_fragments;
    frame.occluded_fragments += band.occluded_fragments;
    frame.lod_fragments += band.lod_fragments;
    frame.sdf_evaluations += band.sdf_evaluations;
    frame.hidden_fragments += band.hidden_fragments;
    frame.hidden_evaluations += band.hidden_evaluations;
    frame.covered_pixels += band.covered_pixels;
}

// The box-local ray through pixel (x, y) of a W x H image: from the near plane (ro) along unit rd.
struct PixelRay {
    vec3 ro, rd;
};
PixelRay pixel_ray(const glm::dmat4& from_clip, int x, int y, int W, int H, const glm::quat& iq, vec3 c) {
    const double nx = (x + 0.5) / W * 2.0 - 1.0, ny = 1.0 - (y + 0.5) / H * 2.0;
    glm::dvec4 near = from_clip * glm::dvec4(nx, ny, -1.0, 1.0);
    glm::dvec4 far = from_clip * glm::dvec4(nx, ny, 1.0, 1.0);
    glm::dvec3 near3 = glm::dvec3(near) / near.w, far3 = glm::dvec3(far) / far.w;
    return {iq * vec3(near3 - glm::dvec3(c)), iq * vec3(glm::normalize(far3 - near3))};
}

// The depth pre-pass of RenderPlan::occluders over rows [row_begin, row_end): per pixel, the
// nearest window depth (1: none) of the occluder boxes of every box (bm_occluder_centre and
// bm_occluder_half of the preset, pulled in by bm_occluder_rounding and pushed back in depth by
// bm_depth_rounding as the pre-pass's vertex stage moves them), as the rasteriser would write
// them; a box that the near plane cuts (the eye inside it among them) draws none, as the shaders'
// pre-pass drops it: its shape may not be drawn where its occluders would lie. normal_matrix: the
// inverse transpose of the object-to-view matrix's 3x3; view_row_y: the projection's clip y per
// view-space unit.
std::vector<float> occluder_depths(const float* origins, const float* quaternions, const float* half_extents,
                                   size_t box_count, const std::vector<glm::ivec4>& rects, const glm::mat4& to_clip,
                                   const glm::dmat4& from_clip, const glm::mat3& normal_matrix, float view_row_y,
                                   SdfPreset kind, int W, int H, size_t row_begin, size_t row_end) {
    std::vector<float> depth((row_end - row_begin) * size_t(W), 1.0f);
    // z + w >= 0 in GL clip space on the near plane's far side
    const vec4 near_side(to_clip[0][2] + to_clip[0][3], to_clip[1][2] + to_clip[1][3], to_clip[2][2] + to_clip[2][3],
                         to_clip[3][2] + to_clip[3][3]);
    const float shape = float(int(kind));
    for (size_t b = 0; b < box_count; ++b) {
        const glm::ivec4 r = rects[b];
        if (r.y > int(row_end) - 1 || r.w < int(row_begin) || r.x > r.z) continue;
        const glm::quat q(quaternions[4 * b + 3], quaternions[4 * b], quaternions[4 * b + 1], quaternions[4 * b + 2]);
        const glm::quat iq = glm::conjugate(q);
        const vec3 c = glm::make_vec3(origins + 3 * b), h = glm::make_vec3(half_extents + 3 * b);
        float nearest = glm::dot(vec3(near_side), c) + near_side.w;
        for (int axis = 0; axis < 3; ++axis) {
            vec3 unit(0.0f);
            unit[axis] = 1.0f;
            nearest -= h[axis] * std::abs(glm::dot(vec3(near_side), q * unit));
        }
        if (nearest <= 0.0f) continue;
        // pulled in further for the GPU's rounding (bm_occluder_rounding): a pixel's size at the
        // box's far side (its greatest clip w), and the box's distance from the object's origin
        const vec4 w_row(to_clip[0][3], to_clip[1][3], to_clip[2][3], to_clip[3][3]);
        float farthest = glm::dot(vec3(w_row), c) + w_row.w;
        for (int axis = 0; axis < 3; ++axis) {
            vec3 unit(0.0f);
            unit[axis] = 1.0f;
            farthest += h[axis] * std::abs(glm::dot(vec3(w_row), q * unit));
        }
        // in box-local units across the faces normal to each axis: the view-space pixel times how
        // many object units a plane normal to the axis lies from its parallel per view unit
        // (preview.vert.glsl says why)
        vec3 across;
        for (int axis = 0; axis < 3; ++axis) {
            vec3 unit(0.0f);
            unit[axis] = 1.0f;
            across[axis] = glm::length(normal_matrix * (q * unit));
        }
        const vec3 rounding = shader::bm_occluder_rounding(
                shader::bm_pixel_size(farthest, view_row_y, float(H)) * across, glm::length(c));
        for (float k = 0.0f; k < shader::bm_occluder_count(shape); k += 1.0f) {
            const vec3 centre = shader::bm_occluder_centre(shape, h, k);
            const vec3 extent = shader::bm_occluder_half(shape, h, k) - rounding;
            if (shader::bm_min3(extent) <= 0.0f) continue;
            for (int y = std::max(r.y, int(row_begin)); y <= std::min(r.w, int(row_end) - 1); ++y) {
                for (int x = r.x; x <= r.z; ++x) {
                    const PixelRay ray = pixel_ray(from_clip, x, y, W, H, iq, c);
                    const vec2 span = shader::bm_box_span(ray.ro - centre, ray.rd, extent);
                    if (span.x < 0.0f || span.y < span.x) continue;
                    const vec3 point = c + q * (ray.ro + ray.rd * span.x);
                    const vec4 clip = to_clip * vec4(point, 1.0f);
                    // pushed back by what float32 rounding may move it (bm_depth_rounding), as the
                    // pre-pass's vertex stage pushes its occluders
                    const vec2 spread(
                            glm::dot(glm::abs(vec3(to_clip[0][2], to_clip[1][2], to_clip[2][2])), glm::abs(point)) +
                                    std::abs(to_clip[3][2]),
                            glm::dot(glm::abs(vec3(to_clip[0][3], to_clip[1][3], to_clip[2][3])), glm::abs(point)) +
                                    std::abs(to_clip[3][3]));
                    float& pixel = depth[size_t(y - int(row_begin)) * size_t(W) + size_t(x)];
                    pixel = std::min(pixel, clip.z / clip.w * 0.5f + 0.5f + shader::bm_depth_rounding(spread, clip));
                }
            }
        }
    }
    return depth;
}

template <class Fn>
void parallel_for(size_t count, int threads, Fn fn) {
    const size_t n = std::min(hardware_threads(threads), std::max<size_t>(count / 64, 1));
    run_parallel(n, [&](size_t k) { fn(count * k / n, count * (k + 1) / n); });
}

}  // namespace

float sdf_distance(SdfPreset kind, const float* p, const float* h) {
    if (int(kind) < 0 || int(kind) >= kSdfPresetCount)
        throw std::invalid_argument("unknown SDF preset " + std::to_string(int(kind)));
    return sdf_preset(kind, glm::make_vec3(p), glm::make_vec3(h));
}

void occluder_box(SdfPreset sdf, const float* h, int k, float* centre, float* half_extent) {
    if (int(sdf) < 0 || int(sdf) >= kSdfPresetCount)
        throw std::invalid_argument("unknown SDF preset " + std::to_string(int(sdf)));
    if (k < 0 || k >= kMaxOccluders)
        throw std::invalid_argument("occluder index must be in 0..3, got " + std::to_string(k));
    const float shape = float(int(sdf)), index = float(k);
    const vec3 box = glm::make_vec3(h);
    const bool drawn = index < shader::bm_occluder_count(shape);
    const vec3 c = drawn ? shader::bm_occluder_centre(shape, box, index) : vec3(0.0f);
    const vec3 e = drawn ? shader::bm_occluder_half(shape, box, index) : vec3(0.0f);
    for (int i = 0; i < 3; ++i) centre[i] = c[i], half_extent[i] = e[i];
}

void raymarch(const float* origins, const float* directions, const float* half_extents, size_t ray_count,
              const MarchOptions& o, uint8_t* hit, float* positions, float* normals, int32_t* steps) {
    check_options(o);
    // A zero direction has no ray to march (taking any axis instead would report that axis's hit).
    const size_t still = first_failing(ray_count, [&](size_t i) {
        const float* d = directions + 3 * i;
        return (d[0] == 0.0f) & (d[1] == 0.0f) & (d[2] == 0.0f);
    });
    if (still < ray_count) throw std::invalid_argument("ray " + std::to_string(still) + " has a zero direction");
    parallel_for(ray_count, o.threads, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            vec3 ro = glm::make_vec3(origins + 3 * i);
            vec3 rd = glm::make_vec3(directions + 3 * i);
            vec3 h = glm::make_vec3(half_extents + 3 * i);
            const float len = glm::length(rd);
            // A length whose float32 square underflows or overflows (every component below about
            // 4e-23, or one above about 2e19) is taken in double.
            rd = len > 0.0f && len <= FLT_MAX ? rd / len : vec3(glm::normalize(glm::dvec3(rd)));
            vec2 span = shader::bm_box_span(ro, rd, h);
            float t0 = std::max(span.x, 0.0f);
            March m{false, 0.0f, 0, 0.0f};
            vec3 start = ro + rd * t0;
            if (span.y >= t0) m = bm_march(o.sdf, start, rd, h, std::min(span.y - t0, o.max_distance), o, vec2(0.0f));
            vec3 p = start + rd * m.t;
            if (hit) hit[i] = m.hit ? 1 : 0;
            if (positions)
                for (int k = 0; k < 3; ++k) positions[3 * i + k] = p[k];
            if (normals) {
                vec3 n = m.hit ? bm_normal(o.sdf, p, h, m.d, shader::bm_normal_tap(h)) : vec3(0.0f);
                for (int k = 0; k < 3; ++k) normals[3 * i + k] = n[k];
            }
            if (steps) steps[i] = m.steps;
        }
    });
}

void render_boxes(const float* origins, const float* quaternions, const float* half_extents, size_t box_count,
                  const RenderView& view, const MarchOptions& o, const RenderImages& images, const RenderPlan& plan) {
    check_options(o);
    check_plan(plan, box_count);
    if (!view.object_to_clip || !view.object_to_view || !images.rgba || !images.depth)
        throw std::invalid_argument("render_boxes needs both matrices, rgba and depth");
    const int W = int(view.width), H = int(view.height);
    const glm::mat4 to_clip = glm::make_mat4(view.object_to_clip);
    const glm::dmat4 from_clip = glm::inverse(glm::dmat4(to_clip));
    const glm::mat4 to_view = glm::make_mat4(view.object_to_view);
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(to_view)));
    // the projection's clip y per view-space unit
    const float view_row_y = float((glm::dmat4(to_clip) * glm::inverse(glm::dmat4(to_view)))[1][1]);
    const vec3 base = glm::make_vec3(view.base_color);
    const float row_y = glm::length(vec3(to_clip[0][1], to_clip[1][1], to_clip[2][1]));
    const vec4 quality = shader::bm_quality(plan.quality);
    const std::vector<glm::ivec4> rects = pixel_rects(origins, quaternions, half_extents, box_count, to_clip, W, H);
    RenderCost frame_cost;
    std::mutex cost_lock;

    parallel_for(size_t(H), o.threads, [&](size_t row_begin, size_t row_end) {
        RenderCost cost;
        const size_t band_start = row_begin * size_t(W);
        std::vector<int32_t> shown((row_end - row_begin) * size_t(W), -1);
        std::vector<uint8_t> covered(shown.size(), 0);
        const std::vector<float> occluder =
                plan.occluders ? occluder_depths(origins, quaternions, half_extents, box_count, rects, to_clip,
                                                 from_clip, normal_matrix, view_row_y, o.sdf, W, H, row_begin, row_end)
                               : std::vector<float>();
        for (size_t drawn = 0; drawn < box_count; ++drawn) {
            const size_t b = plan.order ? plan.order[drawn] : drawn;
            const glm::ivec4 r = rects[b];
            if (r.y > int(row_end) - 1 || r.w < int(row_begin) || r.x > r.z) continue;
            const glm::quat q(quaternions[4 * b + 3], quaternions[4 * b], quaternions[4 * b + 1],
                              quaternions[4 * b + 2]);
            const glm::quat iq = glm::conjugate(q);
            const vec3 c = glm::make_vec3(origins + 3 * b), h = glm::make_vec3(half_extents + 3 * b);
            auto clip_of = [&](vec3 local) { return to_clip * vec4(c + q * local, 1.0f); };
            auto window_depth = [](vec4 clip) { return clip.z / clip.w * 0.5f + 0.5f; };
            for (int y = std::max(r.y, int(row_begin)); y <= std::min(r.w, int(row_end) - 1); ++y) {
                for (int x = r.x; x <= r.z; ++x) {
                    const PixelRay ray = pixel_ray(from_clip, x, y, W, H, iq, c);
                    const vec3 ro = ray.ro, rd = ray.rd;
                    vec2 span = shader::bm_box_span(ro, rd, h);
                    float t0 = std::max(span.x, 0.0f);
                    if (span.y < t0) continue;
                    const size_t pix = size_t(y) * size_t(W) + size_t(x);
                    ++cost.fragments;
                    covered[pix - band_start] = 1;
                    // The rasterised face: where the ray enters, or (the ray starting inside: the
                    // march from the eye) the far side.
                    const bool from_eye = span.x < 0.0f;
                    const vec3 face = ro + rd * (from_eye ? span.y : span.x);
                    const float face_depth = window_depth(clip_of(face));
                    // (the boxes holding the eye are drawn by a stage that declares no depth, which
                    // the GPU tests late)
                    if (plan.early_depth && !from_eye && !(face_depth >= 0.0f && face_depth < images.depth[pix]))
                        continue;
                    const vec3 start = ro + rd * t0;
                    float t_end = std::min(span.y - t0, o.max_distance);
                    if (plan.occluders) {
                        // Behind the occluders' depth: hidden (a fragment starting inside its box
                        // marches from the eye, so only its march is bounded). The occluders' depth was
                        // cast, not rasterised: no snapped corners, no slope to allow for.
                        const float hidden_from = shader::bm_occluder_limit(occluder[pix - band_start], 0.0f);
                        if (!from_eye && face_depth > hidden_from) {
                            ++cost.occluded_fragments;
                            continue;
                        }
                        const vec4 c0 = to_clip * vec4(c + q * start, 1.0f), c1 = to_clip * vec4(q * rd, 0.0f);
                        t_end = std::min(t_end, shader::bm_depth_crossing(c0, c1, 2.0f * hidden_from - 1.0f));
                    }
                    ++cost.marched_fragments;
                    const float footprint =
                            shader::bm_pixel_size((to_clip * vec4(c + q * face, 1.0f)).w, row_y, float(H));
                    const float box_pixels = 2.0f * shader::bm_max3(h) / footprint;
                    MarchOptions fragment = o;
                    fragment.max_steps = int(shader::bm_step_limit(box_pixels, quality.y, float(o.max_steps)));
                    const bool one_tap = box_pixels < quality.z;
                    cost.lod_fragments += one_tap;
                    March m = one_tap ? bm_one_tap(o.sdf, start, rd, h, t_end, footprint)
                                      : bm_march(o.sdf, start, rd, h, t_end, fragment,
                                                 vec2(quality.x * footprint, quality.w));
                    if (images.steps) images.steps[pix] += m.steps;
                    vec3 local_hit = start + rd * m.t;
                    const Normal normal = m.hit ? normal_by_rule(plan.normal, o.sdf, local_hit, h, m.d, o.epsilon)
                                                : Normal{vec3(0.0f), 0};
                    const int evaluations = m.steps + normal.evaluations;
                    cost.sdf_evaluations += uint64_t(evaluations);
                    if (!m.hit) continue;
                    // never nearer than the face (the declared depth_greater), but a march from the
                    // eye writes its hit's own depth, nearer than its face, the far side
                    // (preview.frag.glsl BM_EYE_BOXES): clamped there, a box nested in the eye's box
                    // between the hit and that far side would show through the hit's surface
                    const vec4 hit_clip = clip_of(local_hit);
                    const float depth = shader::bm_hit_depth(window_depth(hit_clip), hit_clip.w, face_depth, from_eye);
                    if (!(depth >= 0.0f && depth < images.depth[pix])) continue;
                    vec3 n_object = q * normal.n;
                    vec3 color = shader::bm_shade(glm::normalize(normal_matrix * n_object), base);
                    shown[pix - band_start] = evaluations;
                    images.depth[pix] = depth;
                    for (int k = 0; k < 3; ++k) images.rgba[4 * pix + k] = color[k];
                    images.rgba[4 * pix + 3] = 1.0f;
                    if (images.normals)
                        for (int k = 0; k < 3; ++k) images.normals[3 * pix + k] = n_object[k];
                }
            }
        }
        add_band_cost(cost, shown, covered, frame_cost, cost_lock);
    });
    if (plan.cost) *plan.cost = frame_cost;
}

}  // namespace boxmarch
