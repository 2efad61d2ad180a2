#version 450
#extension GL_GOOGLE_include_directive : require
// One full-screen triangle per instance (no inner edge, so every 2 x 2 quad lies wholly inside
// one triangle and a layer shades exactly width x height fragments when width and height are
// even). Instance i draws layer i in front-to-back order and layer L-1-i back to front; layer k
// lies at depth (k + 1) * layer_spacing, layer 0 nearest.
#include "settings.glsl"

layout(location = 0) flat out uint layer;

void main() {
    uint instance = uint(gl_InstanceIndex);
    layer = settings.back_to_front != 0u ? settings.layer_count - 1u - instance : instance;
    vec2 corner = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    gl_Position = vec4(corner, float(layer + 1u) * settings.layer_spacing, 1.0);
}
