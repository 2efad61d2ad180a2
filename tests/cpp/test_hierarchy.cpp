// C++ tests of box_hierarchy's geometric rules (cpp/src/hierarchy_containment.cpp,
// hierarchy_chain.cpp) and of nearest_points (nearest_points.cpp, on the same scenes) against the
// pairwise definitions written out here, loop for loop, in the same double arithmetic (glm, as the
// contract in boxmarch.h states them): every parent and nearest row must be the same, ties
// included, on random scenes built to hit the hard cases (nested boxes, shared origins, equal
// volumes, equal distances, sizes from 1e-4 to 1e4, far-apart clusters, NaN and infinite values,
// quaternions off unit length). A planted wrong parent must be caught. Built with
// BOXMARCH_TESTS=ON and run by ctest, normally and in the sanitizer build.
#include "boxmarch/boxmarch.h"
#include "../../cpp/src/internal.h"  // the searches with their work counted, for the scaling test
#include "../../cpp/src/kd_tree.h"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

using namespace boxmarch;

namespace {

int failures = 0;

struct Scene {
    std::string name;
    std::vector<double> origins, half_extents;
    std::vector<float> quaternions;
    size_t size() const { return origins.size() / 3; }
    void add(glm::dvec3 o, glm::dvec3 h, glm::vec4 q = glm::vec4(0, 0, 0, 1)) {
        origins.insert(origins.end(), {o.x, o.y, o.z});
        half_extents.insert(half_extents.end(), {h.x, h.y, h.z});
        quaternions.insert(quaternions.end(), {q.x, q.y, q.z, q.w});
    }
};

glm::dvec3 at(const std::vector<double>& a, size_t i) { return glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

// The definitions, pair by pair.
bool reference_larger(const Scene& s, size_t a, size_t b) {
    const glm::dvec3 ha = at(s.half_extents, a), hb = at(s.half_extents, b);
    const double va = ha.x * ha.y * ha.z, vb = hb.x * hb.y * hb.z;
    return va > vb || (va == vb && a < b);
}

std::vector<int32_t> reference_containment(const Scene& s) {
    std::vector<int32_t> parent(s.size(), -1);
    for (size_t i = 0; i < s.size(); ++i)
        for (size_t j = 0; j < s.size(); ++j) {
            if (j == i || !reference_larger(s, j, i)) continue;
            const float* q = &s.quaternions[j * 4];
            const glm::dquat to_local = glm::conjugate(glm::dquat(q[3], q[0], q[1], q[2]));
            const glm::dvec3 local = to_local * (at(s.origins, i) - at(s.origins, j));
            const glm::dvec3 h = at(s.half_extents, j);
            const double slack = 1e-6 * std::max(h.x, std::max(h.y, h.z));
            const bool inside = std::abs(local.x) <= h.x + slack && std::abs(local.y) <= h.y + slack &&
                                std::abs(local.z) <= h.z + slack;
            if (inside && (parent[i] < 0 || reference_larger(s, size_t(parent[i]), j))) parent[i] = int32_t(j);
        }
    return parent;
}

std::vector<int32_t> reference_chain(const Scene& s) {
    std::vector<int32_t> parent(s.size(), -1);
    for (size_t i = 0; i < s.size(); ++i) {
        double nearest = std::numeric_limits<double>::infinity();
        for (size_t j = 0; j < i; ++j) {
            const double d = glm::length(at(s.origins, i) - at(s.origins, j));
            if (d < nearest) nearest = d, parent[i] = int32_t(j);
        }
    }
    return parent;
}

std::vector<int32_t> parents_of(const Scene& s, HierarchyRule rule) {
    std::vector<int32_t> parent(s.size(), -7), depth(s.size(), -7);
    box_hierarchy(parent.data(), depth.data(), s.origins.data(), s.quaternions.data(), s.half_extents.data(), s.size(),
                  rule, nullptr);
    return parent;
}

// Number of boxes whose parents differ; prints the first.
size_t differences(const std::vector<int32_t>& got, const std::vector<int32_t>& want) {
    size_t count = 0;
    for (size_t i = 0; i < want.size(); ++i)
        if (got[i] != want[i] && count++ == 0)
            std::fprintf(stderr, "  box %zu: parent %d, the definition says %d\n", i, got[i], want[i]);
    return count + (got.size() != want.size());
}

// Random boxes: sizes log-uniform over 1e-4..1e4 in clusters (some clusters 1e7 away), a few
// with copied origins, copied or permuted half-extents (equal volumes), axis-aligned or turned,
// and children placed inside or on the faces of earlier boxes.
Scene random_scene(uint32_t seed, size_t count, bool lattice) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto pick = [&](size_t n) { return size_t(unit(rng) * double(n)) % n; };
    Scene s;
    s.name = "random seed " + std::to_string(seed) + (lattice ? " (lattice)" : "");
    for (size_t i = 0; i < count; ++i) {
        const double cluster = double(pick(4)) * (unit(rng) < 0.5 ? 1e7 : 50.0);
        glm::dvec3 o = lattice ? glm::dvec3(double(pick(6)), double(pick(6)), double(pick(6)))
                               : glm::dvec3(unit(rng), unit(rng), unit(rng)) * 100.0 - 50.0;
        o.x += cluster;
        glm::dvec3 h(std::pow(10.0, unit(rng) * 8.0 - 4.0));
        h *= glm::dvec3(0.5 + unit(rng), 0.5 + unit(rng), 0.5 + unit(rng));
        glm::vec4 q(0, 0, 0, 1);
        if (unit(rng) < 0.5) {
            const glm::dquat r =
                    glm::normalize(glm::dquat(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
            q = glm::vec4(float(r.x), float(r.y), float(r.z), float(r.w));
        }
        const double kind = unit(rng);
        if (i > 0 && kind < 0.1) {
            o = at(s.origins, pick(i));  // shared origin
        } else if (i > 0 && kind < 0.2) {
            const glm::dvec3 c = at(s.half_extents, pick(i));  // equal volume
            h = unit(rng) < 0.5 ? c : glm::dvec3(c.z, c.x, c.y);
        } else if (i > 0 && kind < 0.45) {
            const size_t p = pick(i);  // inside an earlier box, or on its face (axis-aligned parents)
            const glm::dvec3 ph = at(s.half_extents, p);
            glm::dvec3 f(unit(rng) * 2 - 1, unit(rng) * 2 - 1, unit(rng) * 2 - 1);
            if (unit(rng) < 0.3) f.x = unit(rng) < 0.5 ? -1.0 : 1.0;
            o = at(s.origins, p) + f * ph;
            h = ph * (unit(rng) < 0.5 ? 0.3 : 1.0);
        }
        if (!lattice && unit(rng) < 0.05) h = glm::dvec3(1e4 * (1 + unit(rng)));  // huge
        s.add(o, h, q);
    }
    return s;
}

// Values the definitions treat specially: infinite and zero half-extents, zero and non-unit
// quaternions, coordinates near the double range (box_hierarchy refuses NaN and infinite
// origins and quaternions, negative and NaN half-extents: check_refusals).
Scene special_scene(uint32_t seed) {
    Scene s = random_scene(seed, 300, false);
    s.name = "special values seed " + std::to_string(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const double values[] = {nan, inf, -inf, -1.0, 0.0, 1e305, -1e305, 1e-310};
    for (size_t i = 0; i < s.size(); ++i) {
        const double kind = unit(rng);
        const size_t c = size_t(unit(rng) * 3) % 3;
        const double v = values[size_t(unit(rng) * 8) % 8];
        if (kind < 0.05)
            s.origins[i * 3 + c] = std::isfinite(v) ? v : 1e308;
        else if (kind < 0.1)
            s.half_extents[i * 3 + c] = std::isnan(v) ? inf : std::abs(v);
        else if (kind < 0.15)
            for (int k = 0; k < 4; ++k) s.quaternions[i * 4 + k] *= float(unit(rng) * 2.0);
        else if (kind < 0.18)
            for (int k = 0; k < 4; ++k) s.quaternions[i * 4 + k] = 0.0f;
        else if (kind < 0.2)
            s.quaternions[i * 4 + c] = float(std::isfinite(v) ? std::max(-1e30, std::min(v, 1e30)) : -3e38);
        else if (kind < 0.22)
            for (int k = 0; k < 3; ++k) s.half_extents[i * 3 + k] = inf;
    }
    return s;
}

// Boxes that take the containment search's long-box test (issue 36) and flat boxes, with small
// boxes on their faces, ends and corners: long boxes turned at random, by 1e-6 or not, their longest edge
// 4 times the next (where the search changes its test), just below and far above, some of zero
// thickness, some crossing one point; flat boxes; quaternions of length 0.7 to 1.3; equal sizes
// (ties). The small boxes lie on a face, edge or corner (through the inverse of the map the
// definition applies), half the contract's slack inside or past it, on the slack's end (where
// the rounding of the inside test decides), past it, or anywhere.
Scene long_scene(uint32_t seed, size_t count) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto pick = [&](size_t n) { return size_t(unit(rng) * double(n)) % n; };
    Scene s;
    s.name = "long and flat boxes seed " + std::to_string(seed);
    const size_t holders = count / 3;
    std::vector<glm::dmat3> to_object;
    for (size_t i = 0; i < count; ++i) {
        glm::dquat r = glm::normalize(glm::dquat(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
        if (pick(5) == 0) r = glm::dquat(1, 0, 0, 0);
        if (pick(5) == 0)  // nearly unturned: a slab across the long axis is then nearly as thin as its ends
            r = glm::normalize(
                    glm::dquat(1.0, 1e-6 * (unit(rng) - 0.5), 1e-6 * (unit(rng) - 0.5), 1e-6 * (unit(rng) - 0.5)));
        if (pick(5) == 0) r = r * (0.7 + 0.6 * unit(rng));
        glm::vec4 q(float(r.x), float(r.y), float(r.z), float(r.w));
        const glm::dquat to_local = glm::conjugate(glm::dquat(q.w, q.x, q.y, q.z));
        glm::dmat3 m;
        for (int k = 0; k < 3; ++k) m[k] = to_local * glm::dvec3(k == 0, k == 1, k == 2);
        to_object.push_back(glm::inverse(m));
        glm::dvec3 o = glm::dvec3(unit(rng), unit(rng), unit(rng)) * 20.0 - 10.0;
        glm::dvec3 h = glm::dvec3(unit(rng), unit(rng), unit(rng)) * 0.05 + 0.001;
        if (i < holders) {
            const double ratios[] = {4.0, 3.99, 4.01, 50.0, 1e4}, widths[] = {0.0, 1e-3, 0.02};
            const double width = widths[pick(3)];
            switch (pick(4)) {
                case 0:  // long
                    h = glm::dvec3(std::max(width, 1e-3) * ratios[pick(5)], width, width * (pick(2) ? 1.0 : 0.5));
                    break;
                case 1:  // long, crossing the point (1, 2, 3)
                    h = glm::dvec3(20.0, width, width);
                    o = glm::dvec3(1, 2, 3) + to_object.back()[0] * (unit(rng) * 16.0 - 8.0);
                    break;
                case 2:  // flat
                    h = glm::dvec3(2.0 + 18.0 * unit(rng), 2.0 + 18.0 * unit(rng), width);
                    break;
                default:  // the same as the box before (equal volume, shared origin)
                    if (i > 0) {
                        o = at(s.origins, i - 1), h = at(s.half_extents, i - 1);
                        q = glm::vec4(s.quaternions[4 * i - 4], s.quaternions[4 * i - 3], s.quaternions[4 * i - 2],
                                      s.quaternions[4 * i - 1]);
                        to_object.back() = to_object[i - 1];
                    }
            }
        } else if (pick(5) != 0) {
            const size_t p = pick(holders);
            const glm::dvec3 ph = at(s.half_extents, p);
            const double slack = 1e-6 * std::max(ph.x, std::max(ph.y, ph.z));
            const double past[] = {0.0, -0.5, 0.5, 1.0, 1.5};
            glm::dvec3 local;
            for (int k = 0; k < 3; ++k)
                local[k] = ph[k] * (double(pick(3)) - 1.0) * (pick(2) ? 1.0 : 0.3) + slack * past[pick(5)];
            o = at(s.origins, p) + to_object[p] * local;
        }
        s.add(o, h, q);
    }
    return s;
}

// nearest_points: the scene's odd boxes' origins searched among its even boxes' origins, against
// the definition in its contract (squares of the coordinates scaled so the largest finite one
// stays below 2^300, summed in order; ties to the lowest row; non-finite: never taken, -1).
std::vector<int64_t> reference_nearest(const std::vector<double>& points, const std::vector<double>& candidates) {
    auto finite = [](const double* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); };
    double largest = 0.0;
    for (const std::vector<double>* set : {&points, &candidates})
        for (size_t i = 0; i < set->size() / 3; ++i)
            if (finite(&(*set)[3 * i]))
                for (int k = 0; k < 3; ++k) largest = std::max(largest, std::abs((*set)[3 * i + k]));
    int exponent;
    std::frexp(largest, &exponent);
    const double scale = exponent > 300 ? std::ldexp(1.0, 300 - exponent) : 1.0;
    std::vector<int64_t> nearest(points.size() / 3, -1);
    for (size_t i = 0; i < nearest.size(); ++i) {
        double best = std::numeric_limits<double>::infinity();
        for (size_t j = 0; j < candidates.size() / 3 && finite(&points[3 * i]); ++j) {
            if (!finite(&candidates[3 * j])) continue;
            double d2 = 0.0;
            for (int k = 0; k < 3; ++k) {
                const double d = points[3 * i + k] * scale - candidates[3 * j + k] * scale;
                d2 += d * d;
            }
            if (d2 < best || nearest[i] < 0) best = d2, nearest[i] = int64_t(j);
        }
    }
    return nearest;
}

void check_nearest(const Scene& s) {
    std::vector<double> points, candidates;
    for (size_t i = 0; i < s.origins.size(); ++i) (i / 3 % 2 ? points : candidates).push_back(s.origins[i]);
    const std::vector<int64_t> want = reference_nearest(points, candidates);
    for (int threads : {1, 0}) {
        std::vector<int64_t> got(want.size(), -7);
        nearest_points(got.data(), points.data(), want.size(), candidates.data(), candidates.size() / 3, threads);
        for (size_t i = 0; i < want.size(); ++i)
            if (got[i] != want[i]) {
                ++failures;
                std::fprintf(stderr, "FAIL %s: point %zu nearest %lld, the definition says %lld\n", s.name.c_str(), i,
                             (long long)got[i], (long long)want[i]);
                return;
            }
    }
}

// NaN and infinite origins and quaternion components, negative and NaN half-extents: refused by
// every rule, naming the box, with nothing written.
void check_refusals() {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (HierarchyRule rule : {HierarchyRule::Given, HierarchyRule::Containment, HierarchyRule::Chain})
        for (int field = 0; field < 3; ++field)
            for (double bad : {nan, inf, -inf, -1.0}) {
                if (field == 2 && bad == inf) continue;  // an infinite half-extent is a size
                Scene s = random_scene(9, 5, false);
                if (field == 0) s.origins[3 * 3 + 1] = bad;
                if (field == 1) s.quaternions[3 * 4 + 2] = float(bad);
                if (field == 2) s.half_extents[3 * 3 + 1] = bad;
                if (field < 2 && bad == -1.0) continue;  // a valid coordinate
                std::vector<int32_t> parent(5, 7), depth(5, 7), given(5, -1);
                std::string message;
                try {
                    box_hierarchy(parent.data(), depth.data(), s.origins.data(), s.quaternions.data(),
                                  s.half_extents.data(), 5, rule, given.data());
                } catch (const std::invalid_argument& e) {
                    message = e.what();
                }
                if (message.rfind("box 3 has ", 0) != 0 || parent[0] != 7 || depth[0] != 7)
                    ++failures, std::fprintf(stderr, "FAIL refusal rule %d field %d value %g: '%s'\n", int(rule), field,
                                             bad, message.c_str());
            }
}

void check_scene(const Scene& s) {
    try {
        const size_t containment = differences(parents_of(s, HierarchyRule::Containment), reference_containment(s));
        const size_t chain = differences(parents_of(s, HierarchyRule::Chain), reference_chain(s));
        if (containment || chain) {
            ++failures;
            std::fprintf(stderr, "FAIL %s: %zu containment and %zu chain parents differ\n", s.name.c_str(), containment,
                         chain);
        }
    } catch (const std::exception& e) {  // e.g. a cycle: the definitions cannot make one
        ++failures;
        std::fprintf(stderr, "FAIL %s: %s\n", s.name.c_str(), e.what());
    }
}

// Scaling: the work each search does per box (tree nodes reached and boxes measured, counted by
// the core) on scenes of n and 2n boxes. A search that compares every pair does twice the work
// per box at 2n; these must stay below kGrowthLimit, on the random scenes and on the shapes that
// made the earlier grids pairwise: queries 10 and 1e9 units from a compact set of candidates,
// clusters 1e9 apart, long thin boxes crossing one region, boxes at one origin, nested boxes.
constexpr double kGrowthLimit = 1.5;

Scene shaped_scene(const std::string& shape, size_t n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    Scene s;
    s.name = shape + " x" + std::to_string(n);
    for (size_t i = 0; i < n; ++i) {
        glm::dvec3 o(unit(rng), unit(rng), unit(rng)), h(0.01);
        glm::vec4 q(0, 0, 0, 1);
        if (shape == "random") {
            o *= std::cbrt(double(n));
            h = glm::dvec3(0.2 + unit(rng), 0.2 + unit(rng), 0.2 + unit(rng));
        } else if (shape == "clusters 1e9 apart") {
            o.x += 1e9 * double(i % 4);
        } else if (shape == "thin rods crossing one region") {
            h = glm::dvec3(5.0, 0.005, 0.005);
            const glm::dquat r =
                    glm::normalize(glm::dquat(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
            q = glm::vec4(float(r.x), float(r.y), float(r.z), float(r.w));
        } else if (shape == "one origin") {
            o = glm::dvec3(2.0);
            h = glm::dvec3(1.0);
        } else if (shape == "nested, shuffled") {
            o = glm::dvec3(0.0);
            h = glm::dvec3(std::pow(1.0001, double(rng() % 1000000)));
        }
        s.add(o, h, q);
    }
    return s;
}

// Work per box of one search ("containment", "chain", "nearest 10 off", "nearest 1e9 off").
double work_per_box(const std::string& search, const Scene& s) {
    SearchWork work;
    const size_t n = s.size();
    std::vector<int32_t> parent(n);
    if (search == "containment")
        containment_parents(parent.data(), s.origins.data(), s.quaternions.data(), s.half_extents.data(), n, &work);
    else if (search == "chain")
        chain_parents(parent.data(), s.origins.data(), n, &work);
    else {  // the boxes' origins moved away, searched among the boxes' own origins
        std::vector<double> points = s.origins;
        for (size_t i = 0; i < n; ++i) points[3 * i] += search == "nearest 10 off" ? 10.0 : 1e9;
        std::vector<int64_t> nearest(n);
        nearest_points_counted(nearest.data(), points.data(), n, s.origins.data(), n, 0, &work);
    }
    return double(work.nodes + work.candidates) / double(std::max<size_t>(n, 1));
}

void check_scaling() {
    const char* shapes[] = {"random", "clusters 1e9 apart", "thin rods crossing one region", "one origin",
                            "nested, shuffled"};
    const char* searches[] = {"containment", "chain", "nearest 10 off", "nearest 1e9 off"};
    for (const char* shape : shapes)
        for (const char* search : searches) {
            const double small = work_per_box(search, shaped_scene(shape, 20000, 1));
            const double large = work_per_box(search, shaped_scene(shape, 40000, 1));
            const bool ok = large <= kGrowthLimit * small;
            std::printf("%s %-30s %-16s work per box %8.1f at 20,000, %8.1f at 40,000 (x%.2f)\n", ok ? "ok  " : "FAIL",
                        shape, search, small, large, large / small);
            failures += !ok;
        }
    // Long thin boxes are read as their centre lines (issue 36): at 40,000 rods crossing one
    // region the search reads about 210 nodes and origins per box, where the test on the box's
    // and the object's axes alone read about 290.
    const double rods = work_per_box("containment", shaped_scene("thin rods crossing one region", 40000, 1));
    std::printf("%s containment work per box on 40,000 thin rods %.1f (at most 250)\n", rods <= 250 ? "ok  " : "FAIL",
                rods);
    failures += rods > 250;
    // Negative control: the pairwise definition's work (every lower box measured) doubles.
    const double pairwise_small = 20000 / 2.0, pairwise_large = 40000 / 2.0;
    if (pairwise_large <= kGrowthLimit * pairwise_small) ++failures, std::fprintf(stderr, "FAIL scaling control\n");
}

}  // namespace

int main() {
    std::vector<Scene> scenes;
    scenes.push_back(Scene{"no box", {}, {}, {}});
    Scene one{"one box", {}, {}, {}};
    one.add(glm::dvec3(1, 2, 3), glm::dvec3(1));
    scenes.push_back(one);
    Scene same{"equal boxes at one origin", {}, {}, {}};
    for (int i = 0; i < 50; ++i) same.add(glm::dvec3(5, 5, 5), glm::dvec3(2, 1, 0.5));
    scenes.push_back(same);
    for (uint32_t seed = 1; seed <= 6; ++seed) scenes.push_back(random_scene(seed, 1500, false));
    for (uint32_t seed = 1; seed <= 3; ++seed) scenes.push_back(random_scene(100 + seed, 1500, true));
    for (uint32_t seed = 1; seed <= 6; ++seed) scenes.push_back(special_scene(200 + seed));
    for (uint32_t seed = 1; seed <= 6; ++seed) scenes.push_back(long_scene(400 + seed, 900));
    // Clusters near 1e150 and -1e100 (grids scaled down by a power of 2) with a few boxes 1e120
    // wide, and a cluster of boxes 1e-200 apart near the origin.
    Scene wide = random_scene(300, 1200, false);
    wide.name = "clusters 1e150 apart";
    for (size_t i = 0; i < wide.size(); ++i) {
        const double offsets[] = {1e150, -1e100, 0.0};
        wide.origins[i * 3] += offsets[i % 3];
        if (i % 3 == 2)
            for (int k = 0; k < 3; ++k) wide.origins[i * 3 + k] *= 1e-200, wide.half_extents[i * 3 + k] *= 1e-200;
        if (i % 97 == 0)
            for (int k = 0; k < 3; ++k) wide.half_extents[i * 3 + k] = 1e120;
    }
    scenes.push_back(wide);
    // Nested dolls numbered in shuffled order, each at its own slightly moved origin, every fifth
    // size repeated (equal volumes).
    Scene dolls{"800 nested dolls", {}, {}, {}};
    std::vector<int> level(800);
    for (int k = 0; k < 800; ++k) level[k] = k;
    std::shuffle(level.begin(), level.end(), std::mt19937(7));
    for (int k : level) {
        const int size_level = k % 5 == 1 ? k - 1 : k;
        dolls.add(glm::dvec3(1e-3 * (k % 7), 0, 0), glm::dvec3(std::pow(0.99, size_level)),
                  k % 3 ? glm::vec4(0, 0, 0, 1) : glm::vec4(0, 0, 0.6f, 0.8f));
    }
    scenes.push_back(dolls);
    Scene far{"two boxes 1e300 apart", {}, {}, {}};
    far.add(glm::dvec3(-1e300, 0, 0), glm::dvec3(1));
    far.add(glm::dvec3(1e300, 0, 0), glm::dvec3(1e301));
    far.add(glm::dvec3(1e300, 1, 0), glm::dvec3(1));
    scenes.push_back(far);
    size_t roots_held = 0;
    for (const Scene& s : scenes) {
        check_scene(s);
        check_nearest(s);
        for (int32_t p : reference_containment(s)) roots_held += p >= 0;
    }
    // The scenes exercise the rules: many boxes have containment parents.
    if (roots_held < 1000) ++failures, std::fprintf(stderr, "FAIL only %zu boxes held by another\n", roots_held);

    // Negative control: the comparison catches one planted wrong parent.
    const Scene& s = scenes[4];
    std::vector<int32_t> planted = parents_of(s, HierarchyRule::Chain);
    planted[700] = planted[700] == 0 ? 1 : 0;
    if (differences(planted, reference_chain(s)) != 1)
        ++failures, std::fprintf(stderr, "FAIL negative control\n");
    else
        std::printf("(the planted wrong parent above was caught, as it must be)\n");

    check_refusals();
    check_scaling();
    std::printf("%zu scenes, %d failure(s)\n", scenes.size(), failures);
    return failures ? 1 : 0;
}
