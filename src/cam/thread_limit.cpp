#include "cncstream/cam/thread_limit.hpp"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>

namespace cncstream::cam {

void run_with_thread_limit(unsigned threads, const std::function<void()>& work) {
  if (threads == 0) {
    work();
    return;
  }
  const int cores = std::max(1, tbb::info::default_concurrency());
  tbb::task_arena arena(static_cast<int>(std::min<unsigned>(threads, static_cast<unsigned>(cores))));
  arena.execute(work);
}

}  // namespace cncstream::cam
