#pragma once
// Runs an event loop until a condition holds: the tests wait on what the
// machine session did, never on a fixed time. `timeout_s` is a generous bound
// for a loaded machine; the condition, not the time, is the test.
#include <boost/asio/io_context.hpp>
#include <chrono>
#include <functional>
#include <thread>

namespace cncstream::test {

inline bool run_until(boost::asio::io_context& io, const std::function<bool()>& done, double timeout_s = 60,
                      std::chrono::milliseconds slice = std::chrono::milliseconds(20)) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    io.run_for(slice);
    if (io.stopped()) {  // nothing pending: let the simulator's thread answer
      io.restart();
      std::this_thread::sleep_for(slice / 4);
    }
  }
  return true;
}

}  // namespace cncstream::test
