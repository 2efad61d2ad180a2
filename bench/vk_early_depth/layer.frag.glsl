#version 450
#extension GL_GOOGLE_include_directive : require
// One layer's fragment: `iterations` rounds of a hash stand for a march's work; the variant (a
// -D VARIANT_... from build.sh) decides what the shader says about its depth. Every variant but
// no_depth_write writes a depth at or behind the rasterised face's, as boxmarch's march does.
#if defined(VARIANT_DEPTH_GREATER)
layout(depth_greater) out float gl_FragDepth;
#elif defined(VARIANT_DEPTH_UNCHANGED)
layout(depth_unchanged) out float gl_FragDepth;
#elif defined(VARIANT_EARLY_FRAGMENT_TESTS)
layout(early_fragment_tests) in;
#endif

#include "settings.glsl"

layout(location = 0) flat in uint layer;
layout(location = 0) out vec4 colour;

// The sum of `iterations` PCG-style steps' top 10 bits over its largest value, in [0, 1]. It feeds
// the colour (and the depth), so no compiler can drop the loop; the sum of integers stays exact in
// a float up to 16,384 iterations, so a reader can recompute the colour exactly.
float work(uvec2 pixel, uint layer_index) {
    uint state = pixel.x * 1973u + pixel.y * 9277u + layer_index * 26699u;
    float sum = 0.0;
    for (uint i = 0u; i < settings.iterations; ++i) {
        state = state * 747796405u + 2891336453u;
        uint word = ((state >> 16u) ^ state) * 277803737u;
        sum += float(word >> 22u);
    }
    return sum / (1023.0 * float(settings.iterations));
}

void main() {
    float shade = work(uvec2(gl_FragCoord.xy), layer);
    // Red names the layer exactly in an 8-bit target: the read-back check of which layer won.
    colour = vec4(float(layer + 1u) / 255.0, shade, 0.0, 1.0);
#if defined(VARIANT_DEPTH_UNCHANGED)
    gl_FragDepth = gl_FragCoord.z;
#elif !defined(VARIANT_NO_DEPTH_WRITE)
    // Behind the face by a quarter to a half of the gap to the next layer: the front layer still
    // wins, and the depth the shader writes is never nearer than the face (depth_greater holds).
    gl_FragDepth = gl_FragCoord.z + settings.layer_spacing * (0.25 + 0.25 * shade);
#endif
}
