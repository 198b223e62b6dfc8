#pragma once
// The material a live job has removed so far, for the viewer: the program's
// moves, as the machine executes them, cut into a height-field stock with
// the simulator's own removal (cam/stock.hpp), each move with the cutter in
// the spindle at its line. Pure: whoever follows the job (the daemon's
// WebSocket client) feeds it the timeline position; it returns heights.
#include <cstddef>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "cncstream/cam/stock.hpp"
#include "cncstream/viewer/toolpath_buffers.hpp"

namespace cncstream::viewer {

// The cutter in the spindle from a program line (0-based) on.
struct MountedCutter {
  std::size_t line = 0;
  cam::Cutter cutter;
};

// What a cncstream job program says of itself in its comments: each
// operation's cutter from its tool change on (empty for another program),
// and the stock block it was planned from, in work coordinates (nullopt
// when it names none).
std::vector<MountedCutter> program_cutters(std::string_view program);
std::optional<geometry::Box3> program_stock(std::string_view program);

struct LiveCutOptions {
  std::size_t max_nodes = 250'000;  // the stock's step is the finest that keeps to this many nodes
  double min_step = 0.05;           // mm
  double work_z0 = 0;               // where work Z0 is in the path's frame (see LiveCut)
};

class LiveCut {
 public:
  // `path` must outlive this (the viewer's scene holds it). `stock` is the
  // block in the path's frame; without one, the cutting moves' XY extent
  // grown by the largest cutter's radius, up to the highest cutting move
  // across X or Y (plunges start in the air), or up to work Z0 when a cut
  // starts at or above it (programs set Z0 on the stock's top, usually).
  // Throws std::invalid_argument without a cutter or a cutting move.
  LiveCut(const Toolpath& path, std::vector<MountedCutter> cutters, std::optional<geometry::Box3> stock = std::nullopt,
          const LiveCutOptions& options = {});

  // Cuts the segments before timeline position `segments_done` (whole
  // segments) not cut yet, at most `max_segments` of them, in program
  // order; returns how many. A position behind the one reached changes
  // nothing: removed material does not come back.
  std::size_t advance(double segments_done, std::size_t max_segments = std::numeric_limits<std::size_t>::max());
  std::size_t segments_cut() const { return next_; }
  // The cutter in the spindle for the next segment to cut.
  const cam::Cutter& cutter_in_spindle() const { return cutters_[mounted_].cutter; }

  const cam::GridSpec& grid() const { return stock_.grid(); }
  std::vector<float> heights() const;
  double removed_volume() const { return stock_.removed_volume(); }

 private:
  const Toolpath& path_;
  std::vector<MountedCutter> cutters_;  // by line
  cam::HeightFieldStock stock_;
  std::size_t next_ = 0;     // the first segment not cut
  std::size_t mounted_ = 0;  // cutters_[mounted_] is in the spindle at segment next_
};

}  // namespace cncstream::viewer
