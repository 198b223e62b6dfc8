#pragma once
// Turns a raster finishing path into a complete G-code program: header
// (units, absolute mode, plane, spindle on with a dwell), safe retracts,
// the cut, spindle off and program end. Coordinates are placed in the work
// coordinate system chosen by the operator.
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/arc_fit.hpp"
#include "cncstream/geometry/vec3.hpp"

namespace cncstream {

enum class XYOrigin { PartMin, PartCenter, Model };  // work X0 Y0 at ...
enum class ZZero { PartTop, PartBottom, Model };      // work Z0 at ...

// Offset added to model coordinates to get work coordinates.
geometry::Vec3 work_offset(const geometry::Box3& part, XYOrigin xy, ZZero z);

struct MachiningParams {
  double feed = 1000;        // mm/min
  double plunge_feed = 300;  // mm/min
  double rpm = 18000;
  double dwell_s = 2;        // spindle spin-up
  double safe_z = 5;         // work coordinates
  int decimals = 3;
  std::vector<std::string> header_comments;
  // T number written after the header (0: none). GRBL accepts T and ignores
  // it; it names the tool for the operator and for a simulator's tool table.
  int tool = 0;
  // Set: runs of the cut become arcs (G2/G3) where they fit (one-sided over
  // the material, see arc_fit.hpp); unset: straight moves only.
  std::optional<ArcFitOptions> arcs;
};

struct ProgramStats {
  std::size_t lines = 0;
  std::size_t motion_lines = 0;
  std::size_t arcs = 0;       // G2/G3 moves among them
  double cut_length = 0;      // mm at feed
  double rapid_length = 0;    // mm at rapid
  double feed_time_s = 0;     // cut length / feed (no acceleration)
  geometry::Box3 work_bounds;           // of the tool tip over the cut, in work coordinates
};

// Throws std::invalid_argument if safe_z is not above the whole path.
std::string finishing_program(const cam::RasterPath& path, const geometry::Vec3& offset, const MachiningParams& params,
                              ProgramStats* stats = nullptr);

// The raster as one continuous cut: row, link, row, ...
std::vector<cam::Polyline> raster_as_one_cut(const cam::RasterPath& path);

// Separate cuts (e.g. clean-up pieces): for each, a rapid over its start at
// the safe Z, a plunge at the plunge feed, the cut, a retract.
std::string pieces_program(const std::vector<cam::Polyline>& pieces, const geometry::Vec3& offset, const MachiningParams& params,
                           ProgramStats* stats = nullptr);

class GcodeWriter;

// The start of a one-tool program: header comments, modes, T (if any),
// spindle on and its dwell (if any). And its end: spindle off, M2, and the
// program's line counts into `stats`.
void write_program_start(GcodeWriter& w, const MachiningParams& p);
void write_program_end(GcodeWriter& w, const MachiningParams& p, ProgramStats& stats);

// Fitted moves (fit_arcs) at `feed`: straight moves and G2/G3, their length
// and time added to `stats`; `at` follows the tool. With `bounds`, every
// move's end is added to it.
void write_fitted_moves(GcodeWriter& w, const std::vector<FittedMove>& moves, double feed, ProgramStats& stats,
                        geometry::Vec3& at, geometry::Box3* bounds = nullptr);

// The body of pieces_program, for a program of several operations
// (job_program.hpp): from the safe Z over each piece's start, plunge at the
// plunge feed, cut (arcs where p.arcs), retract to the safe Z. Uses p's
// feeds, decimals, safe_z and arcs; adds to `stats` (not lines). Throws as
// pieces_program.
void write_pieces(GcodeWriter& w, const std::vector<cam::Polyline>& pieces, const geometry::Vec3& offset, const MachiningParams& p,
                  ProgramStats& stats);

}  // namespace cncstream
