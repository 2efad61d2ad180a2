// Offset encoding: local offsets into colour, float or quantisation-aware bytes.
#include "internal.h"

#include <algorithm>
#include <cmath>

namespace boxmarch {

namespace {

double largest_component(const glm::dvec3* offsets, uint32_t count) {
    double m = 0.0;
    for (uint32_t i = 0; i < count; ++i)
        m = std::max({m, std::abs(offsets[i].x), std::abs(offsets[i].y), std::abs(offsets[i].z)});
    return m;
}

uint8_t byte_of(double unit) {  // unit in [0, 1] (clamped), rounded to the nearest byte
    return uint8_t(std::lround(std::clamp(unit, 0.0, 1.0) * 255.0));
}

}  // namespace

float encode_float(const glm::dvec3* offsets, const uint32_t* vertices, uint32_t count, float* rgba) {
    const double largest = largest_component(offsets, count);
    const double scale = largest > kSmallestEncodableOffset ? 1.0 / largest : 1.0;
    for (uint32_t i = 0; i < count; ++i) {
        float* out = rgba + size_t(vertices[i]) * 4;
        for (int k = 0; k < 3; ++k) out[k] = float(0.5 + 0.5 * scale * offsets[i][k]);
        out[3] = float(scale);
    }
    return float(scale);
}

float encode_byte(const glm::dvec3* offsets, const uint32_t* vertices, uint32_t count, uint8_t* rgba) {
    const double largest = largest_component(offsets, count);
    // The largest alpha byte whose range a * |f| <= 1 (plus one, which rounding may still admit).
    const int top = largest > 0.0 ? int(std::min(255.0, std::floor(255.0 / largest) + 1.0)) : 255;
    int best_alpha = std::max(top, 1);
    double best_error = INFINITY;
    for (int alpha = top; alpha >= std::max(1, top - 31); --alpha) {
        const double a = alpha / 255.0;
        double worst = 0.0;
        for (uint32_t i = 0; i < count && worst < best_error; ++i) {
            glm::dvec3 decoded;
            for (int k = 0; k < 3; ++k) decoded[k] = (byte_of(0.5 + 0.5 * a * offsets[i][k]) / 255.0 * 2.0 - 1.0) / a;
            worst = std::max(worst, glm::length(decoded - offsets[i]));
        }
        if (worst < best_error) {
            best_error = worst;
            best_alpha = alpha;
        }
    }
    const double a = best_alpha / 255.0;
    for (uint32_t i = 0; i < count; ++i) {
        uint8_t* out = rgba + size_t(vertices[i]) * 4;
        for (int k = 0; k < 3; ++k) out[k] = byte_of(0.5 + 0.5 * a * offsets[i][k]);
        out[3] = uint8_t(best_alpha);
    }
    return float(a);
}

}  // namespace boxmarch
