// Input checks shared by every entry point: a malformed mesh is rejected before anything is written.
#include "boxmarch/boxmarch.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace boxmarch {

void validate_mesh(const MeshView& mesh) {
    const size_t n = mesh.vertex_count;
    if (n > size_t(INT32_MAX)) throw std::invalid_argument("too many vertices for 32-bit indices");
    if (n && !mesh.positions) throw std::invalid_argument("positions are missing");
    if (mesh.edge_count && !mesh.edges) throw std::invalid_argument("edges are missing");
    if (mesh.face_count && (!mesh.face_starts || !mesh.face_sizes))
        throw std::invalid_argument("face starts or sizes are missing");
    if (mesh.corner_count && !mesh.corner_verts) throw std::invalid_argument("corner vertices are missing");

    for (size_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(mesh.positions[v * 3 + k]))
                throw std::invalid_argument("vertex " + std::to_string(v) +
                                            " has a NaN or infinite coordinate");
    for (size_t e = 0; e < mesh.edge_count * 2; ++e)
        if (mesh.edges[e] < 0 || size_t(mesh.edges[e]) >= n)
            throw std::invalid_argument("edge " + std::to_string(e / 2) + " names vertex " +
                                        std::to_string(mesh.edges[e]) + ", outside 0.." +
                                        std::to_string(n) + "-1");
    for (size_t f = 0; f < mesh.face_count; ++f) {
        const int64_t start = mesh.face_starts[f], size = mesh.face_sizes[f];
        if (size < 3) throw std::invalid_argument("face " + std::to_string(f) + " has fewer than 3 corners");
        if (start < 0 || start + size > int64_t(mesh.corner_count))
            throw std::invalid_argument("face " + std::to_string(f) + " runs outside the corner array");
    }
    for (size_t c = 0; c < mesh.corner_count; ++c)
        if (mesh.corner_verts[c] < 0 || size_t(mesh.corner_verts[c]) >= n)
            throw std::invalid_argument("corner " + std::to_string(c) + " names vertex " +
                                        std::to_string(mesh.corner_verts[c]) + ", outside 0.." +
                                        std::to_string(n) + "-1");
}

}  // namespace boxmarch
