// Counts the fork–join regions a program opens with TBB, and where: loaded with LD_PRELOAD in
// front of libtbb, it stands in for the one entry every blocking TBB algorithm goes through
// (parallel_for, parallel_reduce, parallel_invoke, parallel_sort and task_arena::execute all end
// in tbb::detail::r1::execute_and_wait) and passes each call on to libtbb's own.
//
// Why count them: each region the main thread opens is a barrier on a step's critical path.
// Every thread must arrive before the step goes on, so the more of them a step has, the less a
// step gains from more cores (issue 35: figure 7 gained nothing past 4 threads). Counting needs no
// machine with many cores, and it does not depend on the machine's speed.
//
// At exit it writes to the file named by SOFTBAKE_TBB_REGIONS (stderr when unset) one line per
// call site: the count, whether the main thread or a worker called (a worker's call is a region
// nested in another), then the module and the offset of the caller's return address in it, for
// addr2line (bench/regions_per_step.sh names them).
#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <utility>

// tbb::detail::r1::execute_and_wait(d1::task&, d1::task_group_context&, d1::wait_context&,
// d1::task_group_context&), mangled: the symbol this library defines and the one it looks up.
#define SOFTBAKE_TBB_ENTRY                                                                   \
  "_ZN3tbb6detail2r116execute_and_waitERNS0_2d14taskERNS2_18task_group_contextERNS2_12wait_" \
  "contextES6_"

namespace {

using ExecuteAndWait = void (*)(void*, void*, void*, void*);

ExecuteAndWait real() {
  static const ExecuteAndWait entry = [] {
    auto found = reinterpret_cast<ExecuteAndWait>(dlsym(RTLD_NEXT, SOFTBAKE_TBB_ENTRY));
    if (!found) {
      std::fprintf(stderr, "tbb_regions: libtbb's execute_and_wait not found: %s\n", dlerror());
      std::abort();
    }
    return found;
  }();
  return entry;
}

struct Sites {
  std::mutex mutex;
  std::map<std::pair<bool, std::uintptr_t>, std::uint64_t> calls;  ///< (main thread, caller)

  ~Sites() {
    const char* path = std::getenv("SOFTBAKE_TBB_REGIONS");
    std::FILE* out = path ? std::fopen(path, "w") : stderr;
    if (!out) return;
    for (const auto& [site, count] : calls) {
      Dl_info info{};
      const void* address = reinterpret_cast<const void*>(site.second);
      const bool known = dladdr(address, &info) != 0 && info.dli_fname;
      const std::uintptr_t base = known ? reinterpret_cast<std::uintptr_t>(info.dli_fbase) : 0;
      std::fprintf(out, "%llu %s %s 0x%llx\n", static_cast<unsigned long long>(count),
                   site.first ? "main" : "nested", known ? info.dli_fname : "?",
                   static_cast<unsigned long long>(site.second - base - 1));
    }
    if (out != stderr) std::fclose(out);
  }
};

Sites& sites() {
  static Sites instance;
  return instance;
}

}  // namespace

extern "C" void countedExecuteAndWait(void* task, void* context, void* wait,
                                      void* outer) __asm__(SOFTBAKE_TBB_ENTRY);

extern "C" __attribute__((visibility("default"))) void countedExecuteAndWait(void* task,
                                                                             void* context,
                                                                             void* wait,
                                                                             void* outer) {
  const auto caller = reinterpret_cast<std::uintptr_t>(__builtin_return_address(0));
  const bool main = gettid() == getpid();
  {
    Sites& all = sites();
    std::lock_guard lock(all.mutex);
    ++all.calls[{main, caller}];
  }
  real()(task, context, wait, outer);
}
