// Per-box parameters: one value per submesh from per-element values an artist painted, and the
// per-box random value.
#include "internal.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace boxmarch {

size_t reduce_per_submesh(float* out_values, uint8_t* disagrees, const float* values, size_t element_count,
                          size_t components, const int32_t* submesh_of_element, size_t submesh_count) {
    if (components < 1 || components > 4)
        throw std::invalid_argument("components must be 1..4, got " + std::to_string(components));
    const size_t bad = first_non_finite(values, element_count * components);
    if (bad < element_count * components)
        throw std::invalid_argument("value of element " + std::to_string(bad / components) + " is NaN or infinite");
    std::vector<uint32_t> offsets(submesh_count + 1), items(element_count);
    group_by_submesh(offsets.data(), items.data(), submesh_of_element, element_count, submesh_count);

    const auto tuple_less = [&](uint32_t a, uint32_t b) {
        return std::lexicographical_compare(values + size_t(a) * components, values + size_t(a + 1) * components,
                                            values + size_t(b) * components, values + size_t(b + 1) * components);
    };
    const auto tuple_equal = [&](uint32_t a, uint32_t b) {
        return std::equal(values + size_t(a) * components, values + size_t(a + 1) * components,
                          values + size_t(b) * components);
    };
    size_t disagreeing = 0;
    for (size_t s = 0; s < submesh_count; ++s) {
        uint32_t* first = items.data() + offsets[s];
        uint32_t* last = items.data() + offsets[s + 1];
        float* out = out_values + s * components;
        if (disagrees) disagrees[s] = 0;
        if (first == last) {
            std::fill(out, out + components, 0.0f);
            continue;
        }
        // Stable: within a run of equal tuples the lowest element index comes first.
        std::stable_sort(first, last, tuple_less);
        uint32_t best = *first, best_count = 0, runs = 0;
        for (uint32_t* run = first; run != last;) {
            uint32_t* end = run + 1;
            while (end != last && tuple_equal(*run, *end)) ++end;
            const uint32_t count = uint32_t(end - run);
            if (count > best_count || (count == best_count && *run < best)) {
                best = *run;
                best_count = count;
            }
            ++runs;
            run = end;
        }
        std::copy(values + size_t(best) * components, values + size_t(best + 1) * components, out);
        if (runs > 1) {
            ++disagreeing;
            if (disagrees) disagrees[s] = 1;
        }
    }
    return disagreeing;
}

void box_random(float* out, const uint32_t* fingerprints, size_t count, uint32_t seed) {
    for (size_t i = 0; i < count; ++i) {
        // splitmix64's finaliser over (seed, fingerprint): every input bit reaches the top 24.
        uint64_t z = (uint64_t(seed) << 32 | fingerprints[i]) + 0x9E3779B97F4A7C15ull;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        z ^= z >> 31;
        out[i] = float(z >> 40) * (1.0f / 16777216.0f);
    }
}

}  // namespace boxmarch
