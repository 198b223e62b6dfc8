// The viewer beside a running job (see live_view.hpp).
#include "live_view.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <iostream>
#include <chrono>
#include <cmath>
#include <fstream>

#include "view_follow.hpp"

namespace cncstream::app {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kSurfaceEvery = std::chrono::milliseconds(250);  // the cut's mesh is remade at most this often
constexpr std::size_t kSlice = 2000;  // segments cut between looks at new reports

bool same_cutter(const cam::Cutter& a, const cam::Cutter& b) {
  return a.type == b.type && a.radius == b.radius && a.corner_radius == b.corner_radius &&
         a.half_angle_deg == b.half_angle_deg && a.tip_radius == b.tip_radius && a.grown == b.grown;
}

}  // namespace

// Read in one piece (a 5-million-line program is over 100 MB).
std::string read_program_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) throw std::runtime_error(path + ": cannot open the program");
  std::string text(static_cast<std::size_t>(f.tellg()), '\0');
  f.seekg(0);
  if (!f.read(text.data(), static_cast<std::streamsize>(text.size())))
    throw std::runtime_error(path + ": cannot read the program");
  return text;
}

viewer::CutSurface LiveScene::cut_surface() const {
  const std::vector<float> h = cut->heights();
  if (design) return viewer::cut_surface(cut->grid(), h, *design, tolerance);
  return {viewer::stock_surface(cut->grid(), h), {}};
}

std::string LiveScene::stock_text() const {
  if (!cut) return "no stock (the program names no cutter)";
  return fmt::format("stock {} x {} nodes at {:.3f} mm{}", cut->grid().nx, cut->grid().ny, cut->grid().dx,
                     design ? ", coloured by deviation from the part" : "");
}

std::unique_ptr<LiveScene> make_live_scene(const std::string& program, std::optional<geometry::Mesh> part, bool part_in_work,
                                           std::optional<cam::Cutter> cutter, std::optional<geometry::Box3> part_stock,
                                           double tolerance, double arc_tolerance) {
  auto s = std::make_unique<LiveScene>();
  s->tolerance = tolerance;
  viewer::ToolpathOptions to;
  to.arc_tolerance = arc_tolerance;
  if (part && !part_in_work)
    if (const auto ws = program_work_origin(program, part->bounds())) to.offset = -ws->offset;
  s->offset = to.offset;
  s->scene.program = viewer::build_toolpath(program, to);

  std::vector<viewer::MountedCutter> cutters = viewer::program_cutters(program);
  if (cutters.empty() && cutter) cutters.push_back({0, *cutter});
  if (!cutters.empty()) {
    s->scene.cutter = cutters.front().cutter;
    std::optional<geometry::Box3> stock = viewer::program_stock(program);
    if (stock) stock = geometry::Box3{stock->lo + s->offset, stock->hi + s->offset};
    else if (part_stock) stock = part_stock;
    else if (part) stock = part->bounds();  // as the simulator takes it: the part's box
    viewer::LiveCutOptions lo;
    lo.work_z0 = s->offset.z;
    s->cut.emplace(*s->scene.program, std::move(cutters), stock, lo);
    if (part) s->design = cam::design_heights(*part, s->cut->grid());
  }
  // With the removed material shown, the part is inside the stock (the
  // cut's colours compare with it); without, the part itself.
  if (part && !s->cut) s->scene.part = viewer::part_surface(*part);
  return s;
}

double segments_before_line(const viewer::Toolpath& path, long executing_line) {
  if (executing_line <= 1) return 0;
  const auto line = static_cast<std::uint32_t>(executing_line - 1);  // 0-based, in progress
  const auto it = std::lower_bound(path.segments.begin(), path.segments.end(), line,
                                   [](const viewer::SegmentInfo& s, std::uint32_t l) { return s.line < l; });
  return static_cast<double>(it - path.segments.begin());
}

LiveFeed::LiveFeed(LiveScene& scene, viewer::LiveCursor& live) : s_(scene), live_(live) {
  thread_ = std::thread([this] { run(); });
}

LiveFeed::~LiveFeed() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void LiveFeed::position(const geometry::Vec3& work_position) { live_.set_cutter_position(work_position + s_.offset); }

void LiveFeed::progress(double segments_done, const std::string& status) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    target_ = std::max(target_, segments_done);
    status_ = status;
  }
  wake_.notify_all();
}

void LiveFeed::end(double segments_done, const std::string& status) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    target_ = std::max(target_, segments_done);
    status_ = status;
    ended_ = true;
  }
  wake_.notify_all();
}

void LiveFeed::wait_ended() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [this] { return caught_up_ || stop_; });
}

double LiveFeed::segments_cut() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return s_.cut ? static_cast<double>(s_.cut->segments_cut()) : std::floor(target_);
}

double LiveFeed::removed_volume() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return s_.cut ? s_.cut->removed_volume() : 0;
}

void LiveFeed::run() {
  double shown_progress = -1;
  std::string shown_status;
  cam::Cutter shown_cutter = s_.scene.cutter.value_or(cam::Cutter{});
  auto last_surface = Clock::now() - kSurfaceEvery;
  bool stale = false;  // the cut changed since its mesh was sent
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    const double target = target_;
    const bool ended = ended_;
    const std::string status = status_;
    lock.unlock();
    bool cut_some = false;
    if (s_.cut && static_cast<double>(s_.cut->segments_cut()) < std::floor(target)) {
      s_.cut->advance(target, kSlice);
      cut_some = stale = true;
      if (!same_cutter(s_.cut->cutter_in_spindle(), shown_cutter)) live_.set_cutter(shown_cutter = s_.cut->cutter_in_spindle());
    }
    const bool caught_up = !s_.cut || static_cast<double>(s_.cut->segments_cut()) >= std::floor(target);
    if (stale && ((ended && caught_up) || Clock::now() - last_surface >= kSurfaceEvery)) {
      live_.set_cut(std::make_shared<const viewer::TriangleMesh>(s_.cut_surface().mesh));
      last_surface = Clock::now();
      stale = false;
    }
    // Only what changed wakes the window.
    const double shown = s_.cut ? static_cast<double>(s_.cut->segments_cut()) : std::floor(target);
    if (shown != shown_progress) live_.set_progress(shown_progress = shown);
    if (status != shown_status) live_.set_status(shown_status = status);
    lock.lock();
    if (ended && caught_up && !stale && target == target_ && !caught_up_) {
      caught_up_ = true;
      wake_.notify_all();
    }
    if (cut_some) continue;  // more to cut, between looks at new reports
    if (stale) {
      wake_.wait_until(lock, last_surface + kSurfaceEvery);
    } else {
      wake_.wait(lock, [&] { return stop_ || target_ != target || status_ != status || ended_ != ended; });
    }
  }
}

session::RunResult run_with_viewer(LiveScene& scene, viewer::LiveCursor& live, LiveFeed& feed, const std::string& title,
                                   bool keep_open, const std::function<session::RunResult()>& run_job) {
  std::optional<session::RunResult> result;
  std::exception_ptr error;
  std::atomic<bool> close{false};
  std::thread job([&] {
    try {
      result = run_job();
    } catch (...) {
      error = std::current_exception();
    }
    const bool completed = result && result->outcome == protocol::JobOutcome::Completed;
    const std::string outcome = result ? std::string(protocol::to_string(result->outcome)) : std::string("failed");
    feed.end(completed ? static_cast<double>(scene.scene.program->size()) : 0,
             "job " + outcome + (keep_open ? " (close the window to finish)" : ""));
    if (!keep_open) {
      feed.wait_ended();
      close = true;
      live.set_status("job " + outcome);  // wakes the window to close it
    }
  });
  try {
    viewer::WindowOptions wo;
    wo.title = title;
    wo.live = &live;
    wo.after_frame = [&](const std::string&) { return !close; };
    viewer::run_window(scene.scene, wo);
  } catch (const std::exception& e) {
    std::cerr << "cncstream: no viewer (" << e.what() << "); the job goes on here" << std::endl;
  }
  job.join();
  if (error) std::rethrow_exception(error);
  feed.wait_ended();
  if (scene.cut)
    std::cout << fmt::format("viewer: {:.0f} of {} segments cut into the stock, {:.1f} mm3 removed",
                             feed.segments_cut(), scene.scene.program->size(), feed.removed_volume())
              << std::endl;
  return *result;
}

}  // namespace cncstream::app
