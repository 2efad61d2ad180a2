// The one thread helper of the core: runs parts of a job on std::threads and carries any
// exception a part throws (std::bad_alloc above all) back to the caller, where an exception
// escaping a std::thread would call std::terminate and take the host process (Blender) down.
#include "internal.h"

#include <exception>
#include <thread>

namespace boxmarch {

size_t hardware_threads(int requested) {
    return requested > 0 ? size_t(requested) : std::max<size_t>(1, std::thread::hardware_concurrency());
}

void run_parallel(size_t parts, const std::function<void(size_t)>& work) {
    if (parts <= 1) {
        if (parts == 1) work(0);
        return;
    }
    std::vector<std::exception_ptr> errors(parts);
    auto guarded = [&](size_t part) {
        try {
            work(part);
        } catch (...) {
            errors[part] = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    size_t started = 1;
    try {
        pool.reserve(parts - 1);
        for (; started < parts; ++started) pool.emplace_back(guarded, started);
    } catch (...) {
        // No thread (address space, thread limit): the parts left run on the caller's thread.
    }
    guarded(0);
    for (size_t part = started; part < parts; ++part) guarded(part);
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace boxmarch
