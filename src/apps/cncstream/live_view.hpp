#pragma once
// The viewer beside a job that runs: followed on the daemon (view_follow),
// or streamed by this process (`cncstream FILE PORT --view`). LiveScene is
// the program (and part) as the viewer shows them with the stock the moves
// cut; LiveFeed turns the job's reports into the window's updates on a
// thread of its own, so whoever reports (the daemon's socket reader, a
// streaming session's tick) never waits for the cutting or the meshing.
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "cncstream/cam/deviation.hpp"
#include "cncstream/session/stream_runner.hpp"
#include "cncstream/viewer/live_cut.hpp"
#include "cncstream/viewer/scene.hpp"
#include "cncstream/viewer/window.hpp"

namespace cncstream::app {

struct LiveScene {
  viewer::Scene scene;
  geometry::Vec3 offset{};  // work coordinates -> the scene's frame
  std::optional<viewer::LiveCut> cut;  // without a cutter: none
  std::optional<cam::DesignHeights> design;
  double tolerance = 0.05;

  // The stock as it stands: coloured by its deviation from the part, plain without one.
  viewer::CutSurface cut_surface() const;
  // "stock 601 x 401 nodes at 0.050 mm[, coloured by deviation from the part]"
  std::string stock_text() const;
};

// The scene of `program`: `part` placed by the work origin the program's
// header names (or as it is, in work coordinates, with `part_in_work`);
// each operation's cutter from the program's comments, else `cutter`; the
// stock the program names, else `part_stock` (in the part's frame), else
// the part's box (as the simulator takes it), else the moves' extent. Held
// by pointer: the cut refers to the scene's path.
std::unique_ptr<LiveScene> make_live_scene(const std::string& program, std::optional<geometry::Mesh> part, bool part_in_work,
                                           std::optional<cam::Cutter> cutter, std::optional<geometry::Box3> part_stock,
                                           double tolerance, double arc_tolerance);

// A program read in one piece (a 5-million-line program is over 100 MB);
// std::runtime_error naming the file when it cannot be read.
std::string read_program_text(const std::string& path);

// The timeline position of an executing line (1-based; the lines before it
// have run).
double segments_before_line(const viewer::Toolpath& path, long executing_line);

class LiveFeed {
 public:
  LiveFeed(LiveScene& scene, viewer::LiveCursor& live);
  ~LiveFeed();
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  // From any thread; each returns at once.
  void position(const geometry::Vec3& work_position);
  void progress(double segments_done, const std::string& status);
  void end(double segments_done, const std::string& status);
  // After end(): waits until every move up to the end is cut and shown.
  void wait_ended();
  // Once ended: the segments cut and the volume removed.
  double segments_cut() const;
  double removed_volume() const;

 private:
  void run();
  LiveScene& s_;
  viewer::LiveCursor& live_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  double target_ = 0;
  std::string status_;
  bool ended_ = false, caught_up_ = false, stop_ = false;
  std::thread thread_;  // last: started once the rest is set
};

// Runs `run_job` (a streaming session) on a thread of its own while the
// window shows `scene` on this one (GLFW wants the main thread), then
// returns its result. The job ends by itself: closing the window changes
// nothing on the machine, and a window that cannot open is said on stderr
// while the job goes on. At the job's end the window closes unless
// `keep_open` (an operator at the terminal closes it after a look).
session::RunResult run_with_viewer(LiveScene& scene, viewer::LiveCursor& live, LiveFeed& feed, const std::string& title,
                                   bool keep_open, const std::function<session::RunResult()>& run_job);

}  // namespace cncstream::app
