// Frame derivation: which faces (or edges) orient a submesh, the frame they span, its quaternion,
// and the 24 axis-aligned turns an artist can apply on top. Face vectors are Newell's (M. E. Newell's
// polygon normal, as in Sutherland, Sproull and Schumacker 1974); the quaternion comes from glm::quat_cast,
// Shepperd's method (Shepperd 1978: start from the largest of w, x, y, z).
#include "internal.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace boxmarch {

namespace {

// Newell's vector of face f (twice its vector area): robust for non-planar and concave polygons.
// Triangles and quads, nearly every face, take the one-cross-product form of the same sum.
// Writes the face's perimeter when asked.
glm::dvec3 face_vector(const SubmeshView& s, uint32_t f, double* perimeter) {
    const MeshView& m = *s.mesh;
    const int32_t* corners = m.corner_verts + m.face_starts[f];
    const int32_t n = m.face_sizes[f];
    const glm::dvec3 p0 = s.position(uint32_t(corners[0]));
    glm::dvec3 sum;
    if (n == 3) {
        sum = glm::cross(s.position(uint32_t(corners[1])) - p0, s.position(uint32_t(corners[2])) - p0);
    } else if (n == 4) {
        // cross(p1-p0, p2-p0) + cross(p2-p0, p3-p0) = cross(p2-p0, p3-p1)
        sum = glm::cross(s.position(uint32_t(corners[2])) - p0,
                         s.position(uint32_t(corners[3])) - s.position(uint32_t(corners[1])));
    } else {
        sum = glm::dvec3(0.0);
        glm::dvec3 prev = s.position(uint32_t(corners[1])) - p0;
        for (int32_t c = 2; c < n; ++c) {
            const glm::dvec3 cur = s.position(uint32_t(corners[c])) - p0;
            sum += glm::cross(prev, cur);
            prev = cur;
        }
    }
    if (perimeter) {
        double length = 0.0;
        glm::dvec3 prev = p0;
        for (int32_t c = 1; c <= n; ++c) {
            const glm::dvec3 cur = s.position(uint32_t(corners[c % n]));
            length += glm::length(cur - prev);
            prev = cur;
        }
        *perimeter = length;
    }
    return sum;
}

glm::dvec3 edge_vector(const SubmeshView& s, uint32_t e) {
    const int32_t* ends = s.mesh->edges + size_t(e) * 2;
    return s.position(uint32_t(ends[1])) - s.position(uint32_t(ends[0]));
}

// The unit direction of a vector (zero for a zero vector), the one normalisation every frame
// axis goes through: fresh and cached choices build bit-identical frames from it.
glm::dvec3 unit(const glm::dvec3& v) {
    const double len = glm::length(v);
    return len > 0.0 ? v * (1.0 / len) : glm::dvec3(0.0);
}

// (1 - kTieBand)^2: the tie band on squared sizes.
constexpr double kTieBand2 = (1.0 - kTieBand) * (1.0 - kTieBand);

// Among eligible candidates, the lowest index whose size is within the tie band of the largest.
// Returns -1 when none is eligible. With slack (the copy cache), clears `stable` when a copy's
// displacement could change which candidates are eligible (margin <= 0) or which fall inside the band.
int64_t pick_largest(const std::vector<Candidate>& c, bool slack, bool& stable) {
    double best2 = 0.0;
    size_t best_index = 0;
    for (size_t i = 0; i < c.size(); ++i) {
        if (c[i].eligible && c[i].size2 > best2) {
            best2 = c[i].size2;
            best_index = i;
        }
    }
    if (best2 <= 0.0) return -1;
    const double cut2 = kTieBand2 * best2;
    int64_t pick = -1;
    for (size_t i = 0; i < c.size() && pick < 0; ++i)
        if (c[i].eligible && c[i].size2 >= cut2) pick = int64_t(i);
    if (slack) {
        const Candidate& best = c[best_index];
        const double cut = (1.0 - kTieBand) * best.size;
        for (const Candidate& x : c) {
            if (x.margin <= 0.0) stable = false;
            // The largest itself is inside the band by definition; only the others can cross the cut.
            if (x.eligible && x.size2 != best2 && std::abs(x.size - cut) <= x.size_slack + best.size_slack)
                stable = false;
        }
    }
    return pick;
}

// Marks candidates for the second axis: usable ones more than angle_epsilon off the first axis
// (|cos| below cos_epsilon, compared squared against the unnormalised vectors).
void mark_second(std::vector<Candidate>& c, const Candidate& first, double cos_epsilon, bool slack) {
    const glm::dvec3 axis = unit(first.vector);
    const double cos2 = cos_epsilon * cos_epsilon;
    for (Candidate& x : c) {
        const double d = glm::dot(x.vector, axis);
        x.eligible = x.usable && d * d < cos2 * x.size2;
        if (slack)
            x.margin = x.usable ? std::abs(std::abs(d) / std::sqrt(x.size2) - cos_epsilon) -
                                          (x.angle_slack + first.angle_slack)
                                : 1.0;
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
    // With a displacement (the copy cache), perimeters bound how far it moves areas and normals,
    // and the largest squared perimeter is the scale; without one the largest area stands in.
    double scale2 = 0.0, largest2 = 0.0;
    for (uint32_t i = 0; i < s.face_count; ++i) {
        Candidate& f = faces[i];
        double perimeter = 0.0;
        f.vector = face_vector(s, s.faces[i], d2 > 0.0 ? &perimeter : nullptr);
        f.size2 = glm::dot(f.vector, f.vector);
        largest2 = std::max(largest2, f.size2);
        if (d2 > 0.0) {
            f.size = 0.5 * std::sqrt(f.size2);
            f.size_slack = d2 * perimeter;
            f.angle_slack = f.size > 0.0 ? d2 * perimeter / f.size : 1.0;
            scale2 = std::max(scale2, perimeter * perimeter);
        }
    }
    // Areas this small next to the scale are rounding noise: zero-area faces (compared in
    // squares without a displacement: 4 area^2 against 4 (1e-18 largest area)^2).
    for (Candidate& f : faces) f.usable = d2 > 0.0 ? f.size > 1e-18 * scale2 : f.size2 > 1e-36 * largest2;
}

void measure_edges(const SubmeshView& s, double d2, std::vector<Candidate>& edges) {
    edges.resize(s.edge_count);
    double longest2 = 0.0;
    for (uint32_t i = 0; i < s.edge_count; ++i) {
        Candidate& e = edges[i];
        e.vector = edge_vector(s, s.edges[i]);
        e.size2 = glm::dot(e.vector, e.vector);
        if (d2 > 0.0) {
            e.size = std::sqrt(e.size2);
            e.size_slack = d2;
            e.angle_slack = e.size > 0.0 ? d2 / e.size : 1.0;
        }
        longest2 = std::max(longest2, e.size2);
    }
    for (Candidate& e : edges) e.usable = e.size2 > 1e-18 * longest2;
}

glm::dvec3 orthogonal_part(const glm::dvec3& d, const glm::dvec3& axis) { return d - glm::dot(d, axis) * axis; }

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
    const bool slack = d2 > 0.0;
    FrameChoice choice;
    choice.stable = true;

    measure_faces(s, d2, faces);
    mark_usable(faces);
    const int64_t a = pick_largest(faces, slack, choice.stable);
    if (a >= 0) {
        choice.first_kind = DirectionKind::Face;
        choice.first = uint32_t(a);
        const Candidate first = faces[a];
        mark_second(faces, first, cos_epsilon, slack);
        const int64_t b = pick_largest(faces, slack, choice.stable);
        if (b >= 0) {
            choice.second_kind = DirectionKind::Face;
            choice.second = uint32_t(b);
            return choice;
        }
        measure_edges(s, d2, edges);
        mark_second(edges, first, cos_epsilon, slack);
        const int64_t e = pick_largest(edges, slack, choice.stable);
        choice.second_kind = e >= 0 ? DirectionKind::Edge : DirectionKind::World;
        choice.second = e >= 0 ? uint32_t(e) : 0;
        return choice;
    }
    measure_edges(s, d2, edges);
    mark_usable(edges);
    const int64_t e = pick_largest(edges, slack, choice.stable);
    if (e < 0) return choice;  // Identity: nothing has a direction
    choice.first_kind = DirectionKind::Edge;
    choice.first = uint32_t(e);
    mark_second(edges, edges[e], cos_epsilon, slack);
    const int64_t f = pick_largest(edges, slack, choice.stable);
    choice.second_kind = f >= 0 ? DirectionKind::Edge : DirectionKind::World;
    choice.second = f >= 0 ? uint32_t(f) : 0;
    return choice;
}

glm::dmat3 frame_from_choice(const FrameChoice& choice, const SubmeshView& s, const FrameScratch* measured) {
    // A fresh choice reuses the vectors choose_frame measured: the same function on the same
    // vertices, so the frame is bit for bit the one a cached choice rebuilds.
    auto direction = [&](DirectionKind kind, uint32_t index) {
        if (measured) return unit((kind == DirectionKind::Face ? measured->faces : measured->edges)[index].vector);
        return unit(kind == DirectionKind::Face ? face_vector(s, s.faces[index], nullptr)
                                                : edge_vector(s, s.edges[index]));
    };
    if (choice.first_kind == DirectionKind::None) return glm::dmat3(1.0);
    const glm::dvec3 x = direction(choice.first_kind, choice.first);
    glm::dvec3 y;
    if (choice.second_kind == DirectionKind::World) {
        y = world_second_axis(x);
    } else {
        y = orthogonal_part(direction(choice.second_kind, choice.second), x);
        // Twice is enough (Kahan): where the projection cancelled most of the unit direction (the
        // two directions within 30 degrees), its rounding is no longer small next to y; a second
        // projection leaves y orthogonal to x to double rounding, so the frame is a rotation.
        if (glm::dot(y, y) < 0.25) y = orthogonal_part(y, x);
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
