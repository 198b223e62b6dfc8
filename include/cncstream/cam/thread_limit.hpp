#pragma once
// How many threads a computation may use, on oneTBB's one shared scheduler.
// Every parallel loop of the library runs as oneTBB tasks in the caller's task
// arena, so two jobs computing at once share the cores instead of each
// starting a thread per core. A `threads` parameter of 0 leaves it there (the
// shared pool of all cores, unless the caller limited it); n > 0 runs the work
// in a task arena of its own with n slots (at most n threads, the calling
// thread one of them), capped at the number of cores: oneTBB has no more
// workers than that and warns when an arena asks for more.
#include <functional>

namespace cncstream::cam {

void run_with_thread_limit(unsigned threads, const std::function<void()>& work);

}  // namespace cncstream::cam
