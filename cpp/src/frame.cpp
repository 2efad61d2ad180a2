// Frame derivation: which faces (or edges) orient a submesh, the frame they span, its quaternion,
// and the 24 axis-aligned turns an artist can apply on top.
#include "internal.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace boxmarch {

namespace {

// A candidate direction (face or edge) with the size that ranks it and how far a copy's
// vertex displacement could move that size and the direction itself.

// Newell's normal of face f: robust for non-planar and concave polygons. Writes its unit normal
// and area (the normal is zero when the area is) and, when asked, its perimeter.
void face_measure(const SubmeshView& s, uint32_t f, glm::dvec3& normal, double& area, double* perimeter) {
    const MeshView& m = *s.mesh;
    const int32_t* corners = m.corner_verts + m.face_starts[f];
    const int32_t n = m.face_sizes[f];
    const glm::dvec3 first = s.position(uint32_t(corners[0]));
    glm::dvec3 sum(0.0), prev(0.0);
    double length = 0.0;
    for (int32_t c = 1; c <= n; ++c) {
        const glm::dvec3 cur = c < n ? s.position(uint32_t(corners[c])) - first : glm::dvec3(0.0);
        sum += glm::cross(prev, cur);
        if (perimeter) length += glm::length(cur - prev);
        prev = cur;
    }
    if (perimeter) *perimeter = length;
    const double len = glm::length(sum);
    area = 0.5 * len;
    normal = len > 0.0 ? sum * (1.0 / len) : glm::dvec3(0.0);
}

void edge_measure(const SubmeshView& s, uint32_t e, glm::dvec3& direction, double& length) {
    const int32_t* ends = s.mesh->edges + size_t(e) * 2;
    const glm::dvec3 d = s.position(uint32_t(ends[1])) - s.position(uint32_t(ends[0]));
    length = glm::length(d);
    direction = length > 0.0 ? d / length : glm::dvec3(0.0);
}

// Among eligible candidates, the lowest index whose size is within the tie band of the largest.
// Returns -1 when none is eligible. Clears `stable` when a copy's displacement could change which
// candidates are eligible (margin <= 0) or which fall inside the band.
int64_t pick_largest(const std::vector<Candidate>& c, bool& stable) {
    double best = 0.0, best_slack = 0.0;
    for (const Candidate& x : c) {
        if (x.margin <= 0.0) stable = false;
        if (x.eligible && x.size > best) {
            best = x.size;
            best_slack = x.size_slack;
        }
    }
    if (best <= 0.0) return -1;
    const double cut = (1.0 - kTieBand) * best;
    int64_t pick = -1;
    for (size_t i = 0; i < c.size(); ++i) {
        if (!c[i].eligible) continue;
        // The largest itself is inside the band by definition; only the others can cross the cut.
        if (c[i].size != best && std::abs(c[i].size - cut) <= c[i].size_slack + best_slack) stable = false;
        if (pick < 0 && c[i].size >= cut) pick = int64_t(i);
    }
    return pick;
}

// Marks candidates for the second axis: usable ones more than angle_epsilon off the first axis.
void mark_second(std::vector<Candidate>& c, const Candidate& first, double cos_epsilon) {
    for (Candidate& x : c) {
        const double dot = std::abs(glm::dot(x.direction, first.direction));
        x.eligible = x.usable && dot < cos_epsilon;
        x.margin = x.usable ? std::abs(dot - cos_epsilon) - (x.angle_slack + first.angle_slack) : 1.0;
    }
}

// Usable (non-degenerate) candidates are eligible, with nothing near a threshold.
void mark_usable(std::vector<Candidate>& c) {
    for (Candidate& x : c) {
        x.eligible = x.usable;
        x.margin = 1.0;
    }
}

void measure_faces(const SubmeshView& s, double d2, std::vector<Candidate>& faces) {
    faces.resize(s.face_count);
    // Perimeters bound how far a copy's displacement moves areas and normals; without a
    // displacement (no cache) they are not needed, every slack is zero, and the largest area
    // stands in for the squared scale.
    double scale2 = 0.0;
    for (uint32_t i = 0; i < s.face_count; ++i) {
        Candidate& f = faces[i];
        if (d2 > 0.0) {
            double perimeter = 0.0;
            face_measure(s, s.faces[i], f.direction, f.size, &perimeter);
            f.size_slack = d2 * perimeter;
            f.angle_slack = f.size > 0.0 ? d2 * perimeter / f.size : 1.0;
            scale2 = std::max(scale2, perimeter * perimeter);
        } else {
            face_measure(s, s.faces[i], f.direction, f.size, nullptr);
            f.size_slack = 0.0;
            f.angle_slack = f.size > 0.0 ? 0.0 : 1.0;
            scale2 = std::max(scale2, f.size);
        }
    }
    // Areas this small next to the largest face's scale are rounding noise: zero-area faces.
    const double min_area = 1e-18 * scale2;
    for (Candidate& f : faces) f.usable = f.size > min_area;
}

void measure_edges(const SubmeshView& s, double d2, std::vector<Candidate>& edges) {
    edges.resize(s.edge_count);
    double longest = 0.0;
    for (uint32_t i = 0; i < s.edge_count; ++i) {
        edge_measure(s, s.edges[i], edges[i].direction, edges[i].size);
        edges[i].size_slack = d2;
        edges[i].angle_slack = edges[i].size > 0.0 ? d2 / edges[i].size : 1.0;
        longest = std::max(longest, edges[i].size);
    }
    for (Candidate& e : edges) e.usable = e.size > 1e-9 * longest;
}

glm::dvec3 orthogonal_part(const glm::dvec3& d, const glm::dvec3& axis) {
    return d - glm::dot(d, axis) * axis;
}

// The world axis least aligned with `axis` (lowest index on a tie), made orthogonal to it.
glm::dvec3 world_second_axis(const glm::dvec3& axis) {
    int best = 0;
    for (int k = 1; k < 3; ++k)
        if (std::abs(axis[k]) < std::abs(axis[best])) best = k;
    glm::dvec3 w(0.0);
    w[best] = 1.0;
    return glm::normalize(orthogonal_part(w, axis));
}

}  // namespace

FrameSource frame_source(const FrameChoice& choice) {
    if (choice.first_kind == DirectionKind::None) return FrameSource::Identity;
    if (choice.second_kind == DirectionKind::World) return FrameSource::OneAxis;
    if (choice.first_kind == DirectionKind::Edge) return FrameSource::Edges;
    return choice.second_kind == DirectionKind::Face ? FrameSource::Faces : FrameSource::FaceEdge;
}

FrameChoice choose_frame(const SubmeshView& s, double cos_epsilon, double displacement, FrameScratch& scratch) {
    std::vector<Candidate>& faces = scratch.faces;
    std::vector<Candidate>& edges = scratch.edges;
    const double d2 = 2.0 * displacement;
    FrameChoice choice;
    choice.stable = true;

    measure_faces(s, d2, faces);
    mark_usable(faces);
    const int64_t a = pick_largest(faces, choice.stable);
    if (a >= 0) {
        choice.first_kind = DirectionKind::Face;
        choice.first = uint32_t(a);
        const Candidate first = faces[a];
        mark_second(faces, first, cos_epsilon);
        const int64_t b = pick_largest(faces, choice.stable);
        if (b >= 0) {
            choice.second_kind = DirectionKind::Face;
            choice.second = uint32_t(b);
            return choice;
        }
        measure_edges(s, d2, edges);
        mark_second(edges, first, cos_epsilon);
        const int64_t e = pick_largest(edges, choice.stable);
        choice.second_kind = e >= 0 ? DirectionKind::Edge : DirectionKind::World;
        choice.second = e >= 0 ? uint32_t(e) : 0;
        return choice;
    }
    measure_edges(s, d2, edges);
    mark_usable(edges);
    const int64_t e = pick_largest(edges, choice.stable);
    if (e < 0) return choice;  // Identity: nothing has a direction
    choice.first_kind = DirectionKind::Edge;
    choice.first = uint32_t(e);
    mark_second(edges, edges[e], cos_epsilon);
    const int64_t f = pick_largest(edges, choice.stable);
    choice.second_kind = f >= 0 ? DirectionKind::Edge : DirectionKind::World;
    choice.second = f >= 0 ? uint32_t(f) : 0;
    return choice;
}

glm::dmat3 frame_from_choice(const FrameChoice& choice, const SubmeshView& s, const FrameScratch* measured) {
    // A fresh choice reuses the directions choose_frame measured: the same function on the same
    // vertices, so the frame is bit for bit the one a cached choice rebuilds.
    auto direction = [&](DirectionKind kind, uint32_t index) {
        if (measured) return (kind == DirectionKind::Face ? measured->faces : measured->edges)[index].direction;
        glm::dvec3 d;
        double size;
        if (kind == DirectionKind::Face) face_measure(s, s.faces[index], d, size, nullptr);
        else edge_measure(s, s.edges[index], d, size);
        return d;
    };
    if (choice.first_kind == DirectionKind::None) return glm::dmat3(1.0);
    const glm::dvec3 x = direction(choice.first_kind, choice.first);
    glm::dvec3 y;
    if (choice.second_kind == DirectionKind::World) {
        y = world_second_axis(x);
    } else {
        y = orthogonal_part(direction(choice.second_kind, choice.second), x);
        const double len = glm::length(y);
        y = len > 0.0 ? y / len : world_second_axis(x);
    }
    return glm::dmat3(x, y, glm::cross(x, y));
}

glm::dvec4 quaternion_from_frame(const glm::dmat3& frame) {
    const glm::dquat q = glm::normalize(glm::quat_cast(frame));
    glm::dvec4 v(q.x, q.y, q.z, q.w);
    // q and -q are the same rotation; pick the one with w > 0, or at w == 0 the one whose first
    // nonzero vector component is positive.
    double lead = v.w;
    for (int k = 0; k < 3 && lead == 0.0; ++k) lead = v[k];
    return lead < 0.0 ? -v : v;
}

bool axis_turn_matrix(double* matrix, int index) {
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    static const int parity[6] = {1, -1, -1, 1, 1, -1};
    if (index < 0 || index >= 24) return false;
    int found = 0;
    for (int p = 0; p < 6; ++p)
        for (int signs = 0; signs < 8; ++signs) {
            const int sx = (signs & 4) ? -1 : 1, sy = (signs & 2) ? -1 : 1, sz = (signs & 1) ? -1 : 1;
            if (parity[p] * sx * sy * sz != 1) continue;
            if (found++ != index) continue;
            const int sign[3] = {sx, sy, sz};
            for (int k = 0; k < 9; ++k) matrix[k] = 0.0;
            for (int col = 0; col < 3; ++col) matrix[col * 3 + perms[p][col]] = sign[col];
            return true;
        }
    return false;
}

}  // namespace boxmarch
