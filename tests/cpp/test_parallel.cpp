// C++ tests of run_parallel (cpp/src/parallel.cpp), the core's one thread helper, which every
// threaded tool runs its parts through: an exception thrown by a part on a worker thread comes
// back to the caller (the first in part order) once every part has run, and never reaches
// std::terminate (which would take Blender down). Built with BOXMARCH_TESTS=ON and run by ctest,
// normally and in the sanitizer build.
#include "../../cpp/src/internal.h"

#include <atomic>
#include <cstdio>
#include <new>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace boxmarch;

namespace {

int failures = 0;

#define CHECK(cond)                                                                \
    do {                                                                           \
        if (!(cond)) {                                                             \
            ++failures;                                                            \
            std::fprintf(stderr, "FAIL (%s:%d): %s\n", __FILE__, __LINE__, #cond); \
        }                                                                          \
    } while (0)

// Runs `parts` parts, those in `throwing` throwing std::runtime_error(their number) (or
// std::bad_alloc when `bad_alloc`); returns the message that reached the caller ("" for none,
// "bad_alloc"), and records in `ran` which parts ran and in `on_worker` which ran off the
// caller's thread.
std::string run_throwing(size_t parts, const std::vector<size_t>& throwing, bool bad_alloc, std::vector<int>& ran,
                         std::vector<int>& on_worker) {
    const std::thread::id caller = std::this_thread::get_id();
    std::vector<std::atomic<int>> ran_flags(parts), worker_flags(parts);
    std::string caught;
    try {
        run_parallel(parts, [&](size_t part) {
            ran_flags[part] = 1;
            worker_flags[part] = std::this_thread::get_id() != caller;
            for (size_t t : throwing)
                if (t == part) {
                    if (bad_alloc) throw std::bad_alloc();
                    throw std::runtime_error(std::to_string(part));
                }
        });
    } catch (const std::bad_alloc&) {
        caught = "bad_alloc";
    } catch (const std::runtime_error& e) {
        caught = e.what();
    }
    ran.assign(parts, 0);
    on_worker.assign(parts, 0);
    for (size_t p = 0; p < parts; ++p) ran[p] = ran_flags[p], on_worker[p] = worker_flags[p];
    return caught;
}

bool all_ran(const std::vector<int>& ran) {
    for (int r : ran)
        if (!r) return false;
    return true;
}

}  // namespace

int main() {
    std::vector<int> ran, on_worker;
    // One worker's allocation failure: carried back to the caller, every part ran.
    CHECK(run_throwing(8, {5}, true, ran, on_worker) == "bad_alloc");
    CHECK(all_ran(ran) && on_worker[5] && !on_worker[0]);
    // Two workers fail: the first in part order comes back.
    CHECK(run_throwing(8, {6, 3}, false, ran, on_worker) == "3");
    CHECK(all_ran(ran) && on_worker[3] && on_worker[6]);
    // The caller's own part fails while the workers run on: its exception, after all of them.
    CHECK(run_throwing(4, {0}, false, ran, on_worker) == "0");
    CHECK(all_ran(ran));
    // Many more parts than cores, one failing late.
    CHECK(run_throwing(64, {63}, false, ran, on_worker) == "63");
    CHECK(all_ran(ran));
    // No failure: nothing thrown; one part runs on the caller's thread; no part runs nothing.
    CHECK(run_throwing(8, {}, false, ran, on_worker).empty() && all_ran(ran));
    CHECK(run_throwing(1, {0}, false, ran, on_worker) == "0" && ran[0] && !on_worker[0]);
    CHECK(run_throwing(0, {}, false, ran, on_worker).empty() && ran.empty());
    std::printf("run_parallel: %d failure(s)\n", failures);
    return failures ? 1 : 0;
}
