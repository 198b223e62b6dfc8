#pragma once
// The thread that owns the pendant's USB receiver: it opens it (and keeps
// trying while none is plugged in), reads input reports and posts each to the
// controller on the session's io_context at once, writes the newest LCD
// frame between reads, and reports an unplug (or a failed transfer) to the
// controller before it waits and reopens. Nothing on the session's thread
// ever blocks on USB.
//
// Destroy it on the session's thread (or after its io_context stopped), and
// before the controller.
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "cncstream/pendant/pendant_controller.hpp"
#include "cncstream/pendant/pendant_usb.hpp"

namespace cncstream::pendant {

struct ReaderOptions {
  std::chrono::milliseconds read_timeout{50};   // also the longest an LCD frame waits
  std::chrono::milliseconds retry_interval{1000};  // without hotplug, how often to look for the receiver
  std::chrono::milliseconds reopen_delay{500};  // after an unplug or a failed transfer
};

class UsbPendantReader {
 public:
  // Starts the thread. `usb` and `controller` must outlive the reader.
  UsbPendantReader(PendantUsb& usb, PendantController& controller, ReaderOptions options = {});
  ~UsbPendantReader();
  UsbPendantReader(const UsbPendantReader&) = delete;
  UsbPendantReader& operator=(const UsbPendantReader&) = delete;
  void stop();

 private:
  void run();
  void post(std::function<void(PendantController&)> fn);
  void lost(const std::string& why);

  PendantUsb& usb_;
  PendantController& controller_;
  ReaderOptions opt_;
  boost::asio::io_context::executor_type executor_;
  std::shared_ptr<bool> alive_;  // posted handlers check it on the session's thread
  std::atomic<bool> stop_{false};
  std::mutex mu_;
  std::optional<DisplayReports> frame_;  // the newest LCD frame not yet written
  std::thread thread_;
};

}  // namespace cncstream::pendant
