// A mesh that owns its arrays, for the C++ tests and the fuzz target: build it with push_back,
// hand the core a MeshView of it.
#pragma once

#include "boxmarch/boxmarch.h"

#include <cstdint>
#include <vector>

namespace boxmarch {

struct OwnedMesh {
    std::vector<float> positions;
    std::vector<int32_t> edges, face_starts, face_sizes, corner_verts;

    MeshView view() const {
        MeshView m;
        m.positions = positions.data();
        m.vertex_count = positions.size() / 3;
        m.edges = edges.data();
        m.edge_count = edges.size() / 2;
        m.face_starts = face_starts.data();
        m.face_sizes = face_sizes.data();
        m.face_count = face_starts.size();
        m.corner_verts = corner_verts.data();
        m.corner_count = corner_verts.size();
        return m;
    }
};

}  // namespace boxmarch
