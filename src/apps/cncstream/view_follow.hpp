#pragma once
// `cncstream view --follow MACHINE`: the viewer as a client of a job on the
// daemon. The program (and an STL job's part) come over the API; the
// WebSocket's status reports move the cutter, the job's executing line moves
// the timeline and cuts the executed moves into a stock (viewer/live_cut),
// so the removed material grows as the machine cuts. With --screenshot, one
// frame of the job as it stands.
#include <optional>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/geometry/vec3.hpp"
#include "cncstream/jobs/work_setup.hpp"
#include "cncstream/viewer/camera.hpp"

namespace cncstream::app {

struct FollowOptions {
  std::string daemon;       // URL; empty: $CNCSTREAM_DAEMON or the default
  std::string machine;
  std::optional<long> job;  // default: the machine's current job, else its first unfinished one
  std::string part;         // a local STL to show instead of an STL job's own
  std::optional<cam::Cutter> cutter;  // for a program that names none (not a cncstream job)
  double tolerance = 0.05;       // deviation within which the cut is on the part, mm
  double arc_tolerance = 0.002;
  bool until_done = false;  // close the window when the job has ended
  // One frame instead of a window.
  std::string screenshot;
  viewer::NamedView view = viewer::NamedView::Iso;
  int width = 1280, height = 800;
};

// Runs the window (or takes the screenshot); the exit code: 0, or 1 when
// the daemon's connection was lost while following.
int follow_job_in_viewer(const FollowOptions& options);

// The work origin a cncstream program names in its header ("work origin: XY
// at part minimum, Z0 at part top"), so its path can be drawn on the part.
std::optional<jobs::WorkSetup> program_work_origin(const std::string& text, const geometry::Box3& part);

}  // namespace cncstream::app
