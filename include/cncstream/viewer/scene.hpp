#pragma once
// What the viewer shows, pure (no GL): any of the part, a program, a
// simulated cut and the cutter, the timeline's position, and what the
// window's readout and scrubber compute from them.
#include <cmath>
#include <optional>
#include <string>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/viewer/scene_mesh.hpp"
#include "cncstream/viewer/toolpath_buffers.hpp"

namespace cncstream::viewer {

struct Scene {
  std::optional<TriangleMesh> part;
  std::optional<CutSurface> cut;
  std::optional<Toolpath> program;
  std::optional<cam::Cutter> cutter;
  std::optional<geometry::Vec3> cutter_at;  // where the cutter is; without it, the timeline's point on the program
  double progress = NAN;          // timeline, in segments of the program; NaN: the whole program done

  bool empty() const { return !part && !cut && !program && !cutter; }
  // Everything shown (the cutter where it stands); empty when nothing is.
  geometry::Box3 bounds() const;
  // The cutter's tip: cutter_at, else the program's point at the timeline
  // (its end when progress is NaN); none without a cutter.
  std::optional<geometry::Vec3> cutter_tip() const;
};

// The timeline's keys: one step is a 500th of the program (at least one
// segment), so a 5-million-segment program is crossed in 500 presses.
double timeline_step(const Scene& scene, double direction);
// A click or drag at window x on the slider (bar_x, bar_w its extent): the
// timeline position under it, clamped to the program.
double timeline_at_bar(double x, int bar_x, int bar_w, std::size_t segments);

// "X 12.345 Y 6.789 Z -1.000" (mm), for the window's title.
std::string format_position(const geometry::Vec3& p);
// "segment 1234 of 5000, line 567" for the timeline's position.
std::string format_progress(const Toolpath& path, double progress);

}  // namespace cncstream::viewer
