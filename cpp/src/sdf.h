// The SDF library of shaders/glsl/sdf.glsl in GLM, function for function, so the CPU reference
// and the viewport preview evaluate the same distances (tests/test_shaders.py compares the
// function lists of GLSL and HLSL; this mirror is checked against known distances in
// tests/test_raymarch_core.py). Units: box-local; h = the box's half-extents.
#pragma once

#include "boxmarch/boxmarch.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>

namespace boxmarch::sdf {

using glm::vec2;
using glm::vec3;

inline float min3(vec3 v) { return std::min(v.x, std::min(v.y, v.z)); }
inline float max3(vec3 v) { return std::max(v.x, std::max(v.y, v.z)); }

// Primitives, centred at the origin.
inline float sd_sphere(vec3 p, float r) { return glm::length(p) - r; }
inline float sd_box(vec3 p, vec3 b) {
    vec3 q = glm::abs(p) - b;
    return glm::length(glm::max(q, vec3(0.0f))) + std::min(max3(q), 0.0f);
}
inline float sd_round_box(vec3 p, vec3 b, float r) { return sd_box(p, b - vec3(r)) - r; }
inline float sd_capsule(vec3 p, vec3 a, vec3 b, float r) {
    vec3 pa = p - a, ba = b - a;
    float hh = glm::clamp(glm::dot(pa, ba) / std::max(glm::dot(ba, ba), 1e-20f), 0.0f, 1.0f);
    return glm::length(pa - ba * hh) - r;
}
inline float sd_cylinder(vec3 p, float r, float half_height) {
    vec2 d = glm::abs(vec2(glm::length(vec2(p.x, p.y)), p.z)) - vec2(r, half_height);
    return std::min(std::max(d.x, d.y), 0.0f) + glm::length(glm::max(d, vec2(0.0f)));
}
inline float sd_torus(vec3 p, float major, float minor) {
    vec2 q = vec2(glm::length(vec2(p.x, p.y)) - major, p.z);
    return glm::length(q) - minor;
}
inline float sd_link(vec3 p, float half_length, float ring, float thickness) {
    vec3 q = vec3(p.x, std::max(std::abs(p.y) - half_length, 0.0f), p.z);
    return glm::length(vec2(glm::length(vec2(q.x, q.y)) - ring, q.z)) - thickness;
}
inline float sd_plane(vec3 p, vec3 n, float offset) { return glm::dot(p, n) + offset; }

// Combinations of two distances.
inline float op_union(float a, float b) { return std::min(a, b); }
inline float op_subtract(float a, float b) { return std::max(a, -b); }
inline float op_intersect(float a, float b) { return std::max(a, b); }
inline float op_smooth_union(float a, float b, float k) {
    float hh = glm::clamp(0.5f + 0.5f * (b - a) / k, 0.0f, 1.0f);
    return glm::mix(b, a, hh) - k * hh * (1.0f - hh);
}
inline float op_smooth_intersect(float a, float b, float k) { return -op_smooth_union(-a, -b, k); }
inline float op_smooth_subtract(float a, float b, float k) { return op_smooth_intersect(a, -b, k); }
inline float op_round(float d, float r) { return d - r; }
inline float op_onion(float d, float thickness) { return std::abs(d) - thickness; }
// Domain repetition: copies every `spacing`, limit copies each side of the centre per axis.
inline vec3 op_repeat_limited(vec3 p, vec3 spacing, vec3 limit) {
    return p - spacing * glm::clamp(glm::floor(p / spacing + 0.5f), -limit, limit);
}

// The presets (shaders/glsl/sdf.glsl, sdf_preset_*).
inline float preset_box(vec3 p, vec3 h) { return sd_box(p, h); }
inline float preset_sphere(vec3 p, vec3 h) { return sd_sphere(p, min3(h)); }
inline float preset_rounded_box(vec3 p, vec3 h) { return sd_round_box(p, h, 0.25f * min3(h)); }
inline float preset_capsule(vec3 p, vec3 h) {
    float r = std::min(h.y, h.z);
    float a = std::max(h.x - r, 0.0f);
    return sd_capsule(p, vec3(-a, 0.0f, 0.0f), vec3(a, 0.0f, 0.0f), r);
}
inline float preset_cylinder(vec3 p, vec3 h) { return sd_cylinder(p, std::min(h.x, h.y), h.z); }
inline float preset_torus(vec3 p, vec3 h) {
    float minor = std::min(h.z, 0.5f * std::min(h.x, h.y));
    return sd_torus(p, std::min(h.x, h.y) - minor, minor);
}
inline float preset_link(vec3 p, vec3 h) {
    float thickness = std::min(h.z, 0.25f * std::min(h.x, h.y));
    return sd_link(vec3(p.y, p.x, p.z), std::max(h.x - h.y, 0.0f), h.y - thickness, thickness);
}

inline float preset(SdfPreset kind, vec3 p, vec3 h) {
    switch (kind) {
        case SdfPreset::Box: return preset_box(p, h);
        case SdfPreset::Sphere: return preset_sphere(p, h);
        case SdfPreset::RoundedBox: return preset_rounded_box(p, h);
        case SdfPreset::Capsule: return preset_capsule(p, h);
        case SdfPreset::Cylinder: return preset_cylinder(p, h);
        case SdfPreset::Torus: return preset_torus(p, h);
        case SdfPreset::Link: return preset_link(p, h);
    }
    return preset_box(p, h);
}

}  // namespace boxmarch::sdf
