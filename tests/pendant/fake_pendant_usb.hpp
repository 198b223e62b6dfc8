#pragma once
// A WHB04B receiver in memory for the reader and controller tests: the test
// plugs it in and out and queues reports; the reader's thread reads them and
// writes LCD frames here. Thread-safe: the test and the reader's thread both
// use it.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "cncstream/pendant/pendant_usb.hpp"

class FakePendantUsb final : public cncstream::pendant::PendantUsb {
 public:
  using Clock = std::chrono::steady_clock;

  // ---- the test's side ---------------------------------------------------
  void plug() {
    std::lock_guard<std::mutex> l(mu_);
    plugged_ = true;
    cv_.notify_all();
  }
  void unplug() {
    std::lock_guard<std::mutex> l(mu_);
    plugged_ = false;
    reports_.clear();
    cv_.notify_all();
  }
  void send(const cncstream::pendant::InputReport& r) {
    std::lock_guard<std::mutex> l(mu_);
    reports_.push_back(r);
    cv_.notify_all();
  }
  std::vector<cncstream::pendant::FeatureReport> features() {
    std::lock_guard<std::mutex> l(mu_);
    return features_;
  }
  std::vector<Clock::time_point> feature_times() {
    std::lock_guard<std::mutex> l(mu_);
    return feature_times_;
  }
  int opens() {
    std::lock_guard<std::mutex> l(mu_);
    return opens_;
  }

  // ---- the reader's side -------------------------------------------------
  bool open(std::string* why) override {
    std::lock_guard<std::mutex> l(mu_);
    if (!plugged_) {
      if (why) *why = "no WHB04B receiver (USB 10ce:eb93) is plugged in";
      return false;
    }
    open_ = true;
    ++opens_;
    return true;
  }
  void close() override {
    std::lock_guard<std::mutex> l(mu_);
    open_ = false;
  }
  bool is_open() const override {
    std::lock_guard<std::mutex> l(mu_);
    return open_;
  }
  cncstream::pendant::UsbReadResult read_report(std::chrono::milliseconds timeout) override {
    using cncstream::pendant::UsbReadStatus;
    std::unique_lock<std::mutex> l(mu_);
    cncstream::pendant::UsbReadResult r;
    cv_.wait_for(l, timeout, [&] { return !plugged_ || !reports_.empty(); });
    if (!plugged_) {
      r.status = UsbReadStatus::Unplugged;
      r.error = "LIBUSB_ERROR_NO_DEVICE (fake)";
    } else if (!reports_.empty()) {
      r.status = UsbReadStatus::Report;
      r.report = reports_.front();
      reports_.pop_front();
    }
    return r;
  }
  bool send_feature_report(const cncstream::pendant::FeatureReport& report, std::string* why) override {
    std::lock_guard<std::mutex> l(mu_);
    if (!plugged_) {
      if (why) *why = "LIBUSB_ERROR_NO_DEVICE (fake)";
      return false;
    }
    features_.push_back(report);
    feature_times_.push_back(Clock::now());
    return true;
  }
  void wait_for_arrival(std::chrono::milliseconds poll) override {
    std::unique_lock<std::mutex> l(mu_);
    cv_.wait_for(l, poll, [&] { return plugged_ || interrupted_; });
    interrupted_ = false;
  }
  void interrupt() override {
    std::lock_guard<std::mutex> l(mu_);
    interrupted_ = true;
    cv_.notify_all();
  }

 private:
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool plugged_ = false, open_ = false, interrupted_ = false;
  int opens_ = 0;
  std::deque<cncstream::pendant::InputReport> reports_;
  std::vector<cncstream::pendant::FeatureReport> features_;
  std::vector<Clock::time_point> feature_times_;
};
