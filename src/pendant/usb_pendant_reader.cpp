#include "cncstream/pendant/usb_pendant_reader.hpp"

#include <boost/asio/post.hpp>

namespace cncstream::pendant {

UsbPendantReader::UsbPendantReader(PendantUsb& usb, PendantController& controller, ReaderOptions options)
    : usb_(usb),
      controller_(controller),
      opt_(options),
      executor_(controller.session().executor()),
      alive_(std::make_shared<bool>(true)) {
  controller_.set_display_sink([this](const DisplayReports& frame) {
    std::lock_guard<std::mutex> l(mu_);
    frame_ = frame;  // only the newest matters: an older one is replaced, not queued
  });
  thread_ = std::thread([this] { run(); });
}

UsbPendantReader::~UsbPendantReader() {
  stop();
  controller_.set_display_sink(nullptr);
  *alive_ = false;
}

void UsbPendantReader::stop() {
  stop_ = true;
  usb_.interrupt();
  if (thread_.joinable()) thread_.join();
  if (usb_.is_open()) usb_.close();
}

void UsbPendantReader::post(std::function<void(PendantController&)> fn) {
  boost::asio::post(executor_, [this, alive = std::weak_ptr<bool>(alive_), fn = std::move(fn)] {
    const auto a = alive.lock();
    if (a && *a) fn(controller_);
  });
}

void UsbPendantReader::lost(const std::string& why) {
  post([why](PendantController& c) { c.unplugged(why); });  // first: the jog cancel must not wait for libusb
  usb_.close();
  usb_.wait_for_arrival(opt_.reopen_delay);
}

void UsbPendantReader::run() {
  std::string last_failure;
  while (!stop_) {
    if (!usb_.is_open()) {
      std::string why;
      if (!usb_.open(&why)) {
        if (why != last_failure)  // say it once, not every second
          post([why](PendantController& c) { c.log(LogLevel::Warning, "pendant: waiting for the receiver: " + why); });
        last_failure = why;
        usb_.wait_for_arrival(opt_.retry_interval);
        continue;
      }
      last_failure.clear();
      {
        std::lock_guard<std::mutex> l(mu_);
        frame_.reset();  // a frame for the previous connection; the controller sends a fresh one
      }
      post([](PendantController& c) { c.connected(); });
    }
    const auto r = usb_.read_report(opt_.read_timeout);
    switch (r.status) {
      case UsbReadStatus::Report:
        post([bytes = r.report](PendantController& c) { c.report(bytes); });
        break;
      case UsbReadStatus::Timeout: break;
      case UsbReadStatus::Malformed:
        post([why = r.error](PendantController& c) { c.log(LogLevel::Warning, "pendant: ignored: " + why); });
        break;
      case UsbReadStatus::Unplugged:
        last_failure = r.error;
        lost(r.error);
        continue;
    }
    std::optional<DisplayReports> frame;
    {
      std::lock_guard<std::mutex> l(mu_);
      frame.swap(frame_);
    }
    if (frame) {
      std::string why;
      for (const auto& part : *frame)
        if (!usb_.send_feature_report(part, &why)) {
          last_failure = why;
          lost(why);
          break;
        }
    }
  }
}

}  // namespace cncstream::pendant
