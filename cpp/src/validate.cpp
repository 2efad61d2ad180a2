// Input checks shared by every entry point: a malformed mesh is rejected before anything is written.
#include "boxmarch/boxmarch.h"
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace boxmarch {

void check_finite_positions(const float* positions, size_t count) {
    const size_t bad = first_non_finite(positions, count * 3);
    if (bad < count * 3)
        throw std::invalid_argument("vertex " + std::to_string(bad / 3) + " has a NaN or infinite coordinate");
}

void validate_mesh(const MeshView& mesh) {
    const size_t n = mesh.vertex_count;
    if (n > size_t(INT32_MAX)) throw std::invalid_argument("too many vertices for 32-bit indices");
    if (n && !mesh.positions) throw std::invalid_argument("positions are missing");
    if (mesh.edge_count && !mesh.edges) throw std::invalid_argument("edges are missing");
    if (mesh.face_count && (!mesh.face_starts || !mesh.face_sizes))
        throw std::invalid_argument("face starts or sizes are missing");
    if (mesh.corner_count && !mesh.corner_verts) throw std::invalid_argument("corner vertices are missing");

    check_finite_positions(mesh.positions, n);
    const size_t bad_end = first_out_of_range(mesh.edges, mesh.edge_count * 2, n);
    if (bad_end < mesh.edge_count * 2)
        throw std::invalid_argument("edge " + std::to_string(bad_end / 2) + " names vertex " +
                                    std::to_string(mesh.edges[bad_end]) + ", outside 0.." + std::to_string(n) + "-1");
    // Sizes and starts in one branch-free sweep; the loop that names the culprit runs only on failure.
    // With start >= 0 and size >= 3, start + size cannot wrap in 32 unsigned bits.
    const uint32_t corner_limit = uint32_t(std::min<size_t>(mesh.corner_count, UINT32_MAX));
    uint32_t faces_bad = 0;
    for (size_t f = 0; f < mesh.face_count; ++f) {
        const int32_t start = mesh.face_starts[f], size = mesh.face_sizes[f];
        faces_bad |= (size < 3) | (start < 0) | (uint32_t(start) + uint32_t(size) > corner_limit);
    }
    for (size_t f = 0; faces_bad && f < mesh.face_count; ++f) {
        const int64_t start = mesh.face_starts[f], size = mesh.face_sizes[f];
        if (size < 3) throw std::invalid_argument("face " + std::to_string(f) + " has fewer than 3 corners");
        if (start < 0 || start + size > int64_t(mesh.corner_count))
            throw std::invalid_argument("face " + std::to_string(f) + " runs outside the corner array");
    }
    const size_t bad_corner = first_out_of_range(mesh.corner_verts, mesh.corner_count, n);
    if (bad_corner < mesh.corner_count)
        throw std::invalid_argument("corner " + std::to_string(bad_corner) + " names vertex " +
                                    std::to_string(mesh.corner_verts[bad_corner]) + ", outside 0.." +
                                    std::to_string(n) + "-1");
}

}  // namespace boxmarch
