#pragma once
// The pendant's USB receiver, behind an interface so everything above it is
// tested without hardware (a fake in the tests, libusb on a machine). Calls
// block: one thread of its own drives them (UsbPendantReader), never the
// session's thread.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "cncstream/pendant/whb04b_display.hpp"
#include "cncstream/pendant/whb04b_report.hpp"

namespace cncstream::pendant {

constexpr std::uint16_t kXhcVendorId = 0x10CE;
constexpr std::uint16_t kWhb04bProductId = 0xEB93;  // WHB04B-4 and -6 (the older HB04, 0xEB70, speaks another protocol)

enum class UsbReadStatus {
  Report,     // `report` holds one input report
  Timeout,    // nothing within the time-out (the pendant only reports changes)
  Malformed,  // a transfer of the wrong size (`error` says what came)
  Unplugged,  // the receiver is gone or a transfer failed: close, and reopen later
};

struct UsbReadResult {
  UsbReadStatus status = UsbReadStatus::Timeout;
  InputReport report{};
  std::string error;
};

class PendantUsb {
 public:
  virtual ~PendantUsb() = default;
  // Finds the receiver by VID:PID and opens it (kernel HID driver detached,
  // interface 0 claimed). False, with the reason in `why`, when none is
  // plugged in or it cannot be opened (permissions: the udev rule).
  virtual bool open(std::string* why) = 0;
  virtual void close() = 0;
  virtual bool is_open() const = 0;
  // Waits up to `timeout` for one input report.
  virtual UsbReadResult read_report(std::chrono::milliseconds timeout) = 0;
  // One LCD feature report (SET_REPORT, wValue 0x0306). False, with the
  // reason, when the transfer fails.
  virtual bool send_feature_report(const FeatureReport& report, std::string* why) = 0;
  // While closed: returns when a receiver may have arrived (a hotplug
  // event where the platform has them), after `poll` at the latest, or at
  // once after interrupt().
  virtual void wait_for_arrival(std::chrono::milliseconds poll) = 0;
  // From any thread: ends a wait_for_arrival early (shutting down).
  virtual void interrupt() = 0;
};

// The libusb-1.0 receiver. Throws std::runtime_error when libusb cannot be
// initialised.
std::unique_ptr<PendantUsb> make_libusb_pendant();

}  // namespace cncstream::pendant
