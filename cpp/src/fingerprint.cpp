// Submesh identity: the copy cache (similar copies share one frame decision) and the exact
// fingerprints behind incremental re-bakes.
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <vector>

namespace boxmarch {

namespace {

uint64_t mix(uint64_t h, uint64_t x) {
    h ^= x * 0x9E3779B97F4A7C15ull;
    h = (h << 31) | (h >> 33);
    return h * 0xBF58476D1CE4E5B9ull;
}

// Appends the submesh's topology to out: its vertices, then each face as its negated size and
// its corners, then each edge's two ends, every vertex taken relative to the submesh's lowest
// one, so a copy made by duplicating geometry (same internal order) yields the same words.
// Offsets are below 2^31, so a negated size (above 2^31 as unsigned) cannot collide with one.
void append_topology(const SubmeshView& s, std::vector<uint32_t>& out) {
    const MeshView& m = *s.mesh;
    size_t corners = 0;
    for (uint32_t i = 0; i < s.face_count; ++i) corners += size_t(m.face_sizes[s.faces[i]]);
    const size_t at = out.size();
    out.resize(at + s.vertex_count + s.face_count + corners + 2 * size_t(s.edge_count));
    uint32_t* w = out.data() + at;
    const uint32_t first = s.vertices[0];
    for (uint32_t i = 0; i < s.vertex_count; ++i) *w++ = s.vertices[i] - first;
    for (uint32_t i = 0; i < s.face_count; ++i) {
        const uint32_t f = s.faces[i];
        const int32_t* corner = m.corner_verts + m.face_starts[f];
        *w++ = 0u - uint32_t(m.face_sizes[f]);
        for (int32_t c = 0; c < m.face_sizes[f]; ++c) *w++ = uint32_t(corner[c]) - first;
    }
    for (uint32_t i = 0; i < s.edge_count; ++i) {
        const int32_t* ends = m.edges + size_t(s.edges[i]) * 2;
        *w++ = uint32_t(ends[0]) - first;
        *w++ = uint32_t(ends[1]) - first;
    }
}

// Rotation anchored on two vertices: x towards vertex i0, y towards i1 (made orthogonal).
bool anchor_frame(const SubmeshView& s, const glm::dvec3& centre, uint32_t i0, uint32_t i1, glm::dmat3& frame) {
    const glm::dvec3 a = s.position(s.vertices[i0]) - centre, b = s.position(s.vertices[i1]) - centre;
    const double la = glm::length(a);
    if (!(la > 0.0)) return false;
    const glm::dvec3 x = a / la;
    glm::dvec3 y = b - glm::dot(b, x) * x;
    const double ly = glm::length(y);
    if (!(ly > 0.0)) return false;
    y /= ly;
    frame = glm::dmat3(x, y, glm::cross(x, y));
    return true;
}

constexpr size_t kMaxStoredVertices = size_t(1) << 20;  // bounds the cache's memory (~40 MB)
constexpr size_t kMaxPerBucket = 4;                     // bounds the work of one lookup

}  // namespace

Spread spread_of(const SubmeshView& s) {
    // One pass of sums; positions are relative to the submesh's base, so the variance formula's
    // cancellation is limited to the submesh's own extent against its spread.
    glm::dvec3 sum(0.0);
    double squares = 0.0;
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const glm::dvec3 p = s.position(s.vertices[i]);
        sum += p;
        squares += glm::dot(p, p);
    }
    const double inv = 1.0 / double(s.vertex_count);
    const glm::dvec3 centre = sum * inv;
    return Spread{centre, std::sqrt(std::max(0.0, squares * inv - glm::dot(centre, centre)))};
}

struct CopyCache::Impl {
    struct Prototype {
        uint32_t vertex_count, face_count, edge_count;
        size_t topology_at, topology_size, positions_at;
        double rms;
        uint32_t anchor0, anchor1;
        glm::dmat3 anchors;
        FrameChoice choice;
    };
    std::vector<Prototype> prototypes;
    std::vector<uint32_t> topology;
    std::vector<uint32_t> scratch;  // the topology of the submesh being looked up
    std::vector<double> positions;
    std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
};

// Counts plus similarity-invariant distance ratios, coarsely quantised: copies land in one
// bucket (a quantisation border only costs a miss, never a wrong match).
uint64_t CopyCache::key(const SubmeshView& s, const Spread& spread) {
    uint64_t h = mix(mix(mix(0, s.vertex_count), s.face_count), s.edge_count);
    if (s.vertex_count < 2 || !(spread.rms > 0.0)) return h;
    const glm::dvec3 p0 = s.position(s.vertices[0]);
    // The first few vertices: for a box these span its edges, so boxes of different proportions
    // spread over many buckets. Squared ratios need no square roots; they are >= 0, so adding
    // one half and truncating rounds them.
    const double inv_rms2 = 1.0 / (spread.rms * spread.rms);
    for (uint32_t i = 1; i < std::min(s.vertex_count, 5u); ++i) {
        const glm::dvec3 d = s.position(s.vertices[i]) - p0;
        h = mix(h, uint64_t(glm::dot(d, d) * inv_rms2 * 1024.0 + 0.5));
    }
    return h;
}

CopyCache::CopyCache(double tolerance) : impl_(new Impl), tolerance_(tolerance) {}
CopyCache::~CopyCache() { delete impl_; }

bool CopyCache::lookup(const SubmeshView& s, const Spread& spread, uint64_t key, FrameChoice& choice) const {
    if (s.vertex_count < 3 || !(spread.rms > 0.0)) return false;
    const auto bucket = impl_->buckets.find(key);
    if (bucket == impl_->buckets.end()) return false;
    impl_->scratch.clear();
    for (uint32_t id : bucket->second) {
        const Impl::Prototype& p = impl_->prototypes[id];
        if (p.vertex_count != s.vertex_count || p.face_count != s.face_count || p.edge_count != s.edge_count) continue;
        std::vector<uint32_t>& words = impl_->scratch;
        if (words.empty()) append_topology(s, words);  // once per lookup, only when needed
        if (words.size() != p.topology_size ||
            !std::equal(words.begin(), words.end(), impl_->topology.begin() + ptrdiff_t(p.topology_at)))
            continue;
        glm::dmat3 anchors;
        if (!anchor_frame(s, spread.centre, p.anchor0, p.anchor1, anchors)) continue;
        const glm::dmat3 rotation = anchors * glm::transpose(p.anchors);
        const double scale = spread.rms / p.rms, limit = tolerance_ * spread.rms;
        const double* stored = impl_->positions.data() + p.positions_at;
        bool fits = true;
        for (uint32_t i = 0; i < s.vertex_count && fits; ++i) {
            const glm::dvec3 q(stored[i * 3], stored[i * 3 + 1], stored[i * 3 + 2]);
            const glm::dvec3 mapped = scale * (rotation * q);
            fits = glm::length(s.position(s.vertices[i]) - spread.centre - mapped) <= limit;
        }
        if (!fits) continue;
        choice = p.choice;
        return true;
    }
    return false;
}

void CopyCache::insert(const SubmeshView& s, const Spread& spread, uint64_t key, const FrameChoice& choice) {
    if (!choice.stable || s.vertex_count < 3 || !(spread.rms > 0.0)) return;
    if (impl_->positions.size() / 3 + s.vertex_count > kMaxStoredVertices) return;
    const glm::dvec3 centre = spread.centre;
    const double rms = spread.rms;
    std::vector<uint32_t>& bucket = impl_->buckets[key];
    if (bucket.size() >= kMaxPerBucket) return;

    // Anchors: the first vertex well away from the centre, then the vertex farthest off that line.
    uint32_t a0 = s.vertex_count;
    for (uint32_t i = 0; i < s.vertex_count && a0 == s.vertex_count; ++i)
        if (glm::length(s.position(s.vertices[i]) - centre) >= 0.5 * rms) a0 = i;
    if (a0 == s.vertex_count) return;
    const glm::dvec3 x = glm::normalize(s.position(s.vertices[a0]) - centre);
    uint32_t a1 = 0;
    double best = 0.0;
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const double off = glm::length(glm::cross(x, s.position(s.vertices[i]) - centre));
        if (off > best) {
            best = off;
            a1 = i;
        }
    }
    Impl::Prototype p;
    // Thin anchors turn noise into rotation error; the fit test still rejects any bad map, so a
    // modest bound only trades misses against reach.
    if (best < 0.01 * rms || !anchor_frame(s, centre, a0, a1, p.anchors)) return;
    p.vertex_count = s.vertex_count;
    p.face_count = s.face_count;
    p.edge_count = s.edge_count;
    p.rms = rms;
    p.anchor0 = a0;
    p.anchor1 = a1;
    p.choice = choice;
    p.topology_at = impl_->topology.size();
    append_topology(s, impl_->topology);
    p.topology_size = impl_->topology.size() - p.topology_at;
    p.positions_at = impl_->positions.size();
    for (uint32_t i = 0; i < s.vertex_count; ++i) {
        const glm::dvec3 q = s.position(s.vertices[i]) - centre;
        impl_->positions.insert(impl_->positions.end(), {q.x, q.y, q.z});
    }
    bucket.push_back(uint32_t(impl_->prototypes.size()));
    impl_->prototypes.push_back(p);
}

uint32_t fingerprint_submesh(const SubmeshView& s, uint32_t seed, std::vector<uint32_t>& words) {
    // The exact position bits, then the topology (relative indices and negated face sizes fit in
    // 32 bits, since vertex counts are below 2^31), gathered into one word list and hashed by four
    // independent lanes that each take 64 bits a round: a quarter of the dependency chain of one
    // running mix, and every lane stays in a register.
    words.resize(size_t(s.vertex_count) * 3);
    for (uint32_t i = 0; i < s.vertex_count; ++i)
        std::memcpy(words.data() + size_t(i) * 3, s.mesh->positions + size_t(s.vertices[i]) * 3, 3 * sizeof(uint32_t));
    append_topology(s, words);
    const uint32_t* w = words.data();
    const size_t n = words.size();
    auto pair = [&](size_t i) { return (uint64_t(w[i]) << 32) | w[i + 1]; };
    uint64_t l0 = mix(seed, s.vertex_count), l1 = 1, l2 = 2, l3 = 3;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        l0 = mix(l0, pair(i));
        l1 = mix(l1, pair(i + 2));
        l2 = mix(l2, pair(i + 4));
        l3 = mix(l3, pair(i + 6));
    }
    for (; i + 2 <= n; i += 2) l0 = mix(l0, pair(i));
    if (i < n) l1 = mix(l1, w[i]);
    const uint64_t h = mix(mix(mix(mix(l0, l1), l2), l3), n);
    const uint32_t folded = uint32_t(h ^ (h >> 32));
    return folded ? folded : 1;  // 0 is reserved for "never baked"
}

}  // namespace boxmarch
