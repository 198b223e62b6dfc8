// The WHB04B receiver through libusb-1.0: synchronous interrupt reads from
// endpoint 0x81 and SET_REPORT control transfers for the LCD, on the
// reader's thread. Arrival is learnt from hotplug callbacks where libusb has
// them (Linux with udev or netlink), else by trying again every `poll`.
#include <libusb.h>

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "cncstream/pendant/pendant_usb.hpp"

namespace cncstream::pendant {

namespace {

constexpr unsigned char kInputEndpoint = 0x81;
constexpr int kInterface = 0;
// Host to device, class request, to the interface (LIBUSB_ENDPOINT_OUT |
// LIBUSB_REQUEST_TYPE_CLASS | LIBUSB_RECIPIENT_INTERFACE; C++20 deprecates
// or-ing those three enums).
constexpr std::uint8_t kSetReportRequestType = 0x21;
constexpr std::uint8_t kHidSetReport = 0x09;
constexpr std::uint16_t kFeatureReport6 = 0x0306;  // report type 3 (feature), id 6
constexpr unsigned kControlTimeoutMs = 100;

std::string usb_error(const char* what, int code) {
  return std::string(what) + ": " + libusb_strerror(static_cast<libusb_error>(code));
}

class LibusbPendant final : public PendantUsb {
 public:
  LibusbPendant() {
    if (const int r = libusb_init(&ctx_); r != 0) throw std::runtime_error(usb_error("cannot initialise libusb", r));
    if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
      const int r = libusb_hotplug_register_callback(
          ctx_, static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
          LIBUSB_HOTPLUG_NO_FLAGS, kXhcVendorId, kWhb04bProductId, LIBUSB_HOTPLUG_MATCH_ANY, &LibusbPendant::on_hotplug,
          this, &hotplug_);
      hotplug_ok_ = r == LIBUSB_SUCCESS;
    }
  }
  ~LibusbPendant() override {
    close();
    if (hotplug_ok_) libusb_hotplug_deregister_callback(ctx_, hotplug_);
    libusb_exit(ctx_);
  }

  bool open(std::string* why) override {
    close();
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx_, &list);
    if (n < 0) {
      if (why) *why = usb_error("cannot list USB devices", static_cast<int>(n));
      return false;
    }
    libusb_device* found = nullptr;
    for (ssize_t i = 0; i < n && !found; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == kXhcVendorId &&
          d.idProduct == kWhb04bProductId)
        found = list[i];
    }
    int r = LIBUSB_ERROR_NOT_FOUND;
    if (found) r = libusb_open(found, &handle_);
    libusb_free_device_list(list, 1);
    if (!found) {
      if (why) *why = "no WHB04B receiver (USB 10ce:eb93) is plugged in";
      return false;
    }
    if (r != 0) {
      handle_ = nullptr;
      if (why)
        *why = r == LIBUSB_ERROR_ACCESS
                   ? std::string("the WHB04B receiver (10ce:eb93) is plugged in but this user may not open it: "
                                 "install packaging/udev/60-cncstream-whb04b.rules (see docs/pendant.md)")
                   : usb_error("cannot open the WHB04B receiver", r);
      return false;
    }
    // The kernel's HID driver owns the receiver by default (it looks like a
    // keyboard); it must let go before we can claim the interface.
    r = libusb_kernel_driver_active(handle_, kInterface);
    if (r == 1) r = libusb_detach_kernel_driver(handle_, kInterface);
    if (r != 0 && r != LIBUSB_ERROR_NOT_SUPPORTED) {
      if (why) *why = usb_error("cannot detach the kernel's HID driver from the WHB04B receiver", r);
      close();
      return false;
    }
    r = libusb_claim_interface(handle_, kInterface);
    if (r != 0) {
      if (why) *why = usb_error("cannot claim the WHB04B receiver's interface 0 (another program uses it?)", r);
      close();
      return false;
    }
    claimed_ = true;
    return true;
  }

  void close() override {
    if (!handle_) return;
    if (claimed_) libusb_release_interface(handle_, kInterface);
    claimed_ = false;
    libusb_close(handle_);
    handle_ = nullptr;
  }

  bool is_open() const override { return handle_ != nullptr; }

  UsbReadResult read_report(std::chrono::milliseconds timeout) override {
    UsbReadResult out;
    if (!handle_) {
      out.status = UsbReadStatus::Unplugged;
      out.error = "the receiver is not open";
      return out;
    }
    unsigned char buf[64];  // more than a report: a wrong-sized transfer is reported, not an overflow
    int got = 0;
    const int r = libusb_interrupt_transfer(handle_, kInputEndpoint, buf, sizeof buf, &got,
                                            static_cast<unsigned>(timeout.count()));
    if (r == LIBUSB_ERROR_TIMEOUT) return out;
    if (r != 0) {
      out.status = UsbReadStatus::Unplugged;
      out.error = usb_error("reading the WHB04B receiver", r);
      return out;
    }
    if (got != static_cast<int>(out.report.size())) {
      out.status = UsbReadStatus::Malformed;
      out.error = "the receiver sent " + std::to_string(got) + " bytes (" +
                  hex_bytes(buf, static_cast<std::size_t>(got)) + "), not an 8-byte report";
      return out;
    }
    std::copy(buf, buf + out.report.size(), out.report.begin());
    out.status = UsbReadStatus::Report;
    return out;
  }

  bool send_feature_report(const FeatureReport& report, std::string* why) override {
    if (!handle_) {
      if (why) *why = "the receiver is not open";
      return false;
    }
    FeatureReport copy = report;  // libusb takes a non-const buffer
    const int r = libusb_control_transfer(
        handle_, kSetReportRequestType, kHidSetReport,
        kFeatureReport6, kInterface, copy.data(), static_cast<std::uint16_t>(copy.size()), kControlTimeoutMs);
    if (r != static_cast<int>(copy.size())) {
      if (why) *why = r < 0 ? usb_error("writing the WHB04B display", r) : "the WHB04B display took a short write";
      return false;
    }
    return true;
  }

  void wait_for_arrival(std::chrono::milliseconds poll) override {
    if (interrupted_.exchange(false)) return;
    if (!hotplug_ok_) {
      std::unique_lock<std::mutex> l(mu_);
      cv_.wait_for(l, poll, [&] { return interrupted_.load(); });
      interrupted_ = false;
      return;
    }
    // Hotplug callbacks run inside libusb's event handling: handle events
    // until the receiver arrives, the poll time passes, or interrupt().
    const auto end = std::chrono::steady_clock::now() + poll;
    while (!arrived_ && !interrupted_) {
      const auto left = end - std::chrono::steady_clock::now();
      if (left <= std::chrono::steady_clock::duration::zero()) break;
      const auto us = std::chrono::duration_cast<std::chrono::microseconds>(left).count();
      timeval tv{static_cast<time_t>(us / 1000000), static_cast<suseconds_t>(us % 1000000)};
      libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
    }
    arrived_ = false;  // an arrival before the wait counts too: it ends the wait at once
    interrupted_ = false;
  }

  void interrupt() override {
    interrupted_ = true;
    cv_.notify_all();
    libusb_interrupt_event_handler(ctx_);
  }

 private:
  static int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device*, libusb_hotplug_event event, void* self) {
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) static_cast<LibusbPendant*>(self)->arrived_ = true;
    return 0;  // stay registered
  }

  libusb_context* ctx_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  bool claimed_ = false;
  bool hotplug_ok_ = false;
  libusb_hotplug_callback_handle hotplug_{};
  std::atomic<bool> arrived_{false};
  std::atomic<bool> interrupted_{false};
  std::mutex mu_;
  std::condition_variable cv_;
};

}  // namespace

std::unique_ptr<PendantUsb> make_libusb_pendant() { return std::make_unique<LibusbPendant>(); }

}  // namespace cncstream::pendant
