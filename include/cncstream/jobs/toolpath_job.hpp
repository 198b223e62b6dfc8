#pragma once
// The finishing tool path job: part (STL or mesh) and cutter -> CL engine,
// zig-zag raster on the G-code's lattice, G-code program. Shared by
// `cncstream toolpath` and the main streaming command.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/raster.hpp"
#include "cncstream/gcode/finishing_program.hpp"
#include "cncstream/gcode/job_program.hpp"
#include "cncstream/gcode/stream_link.hpp"
#include "cncstream/geometry/mesh.hpp"
#include "cncstream/jobs/height_preview.hpp"
#include "cncstream/jobs/job_control.hpp"
#include "cncstream/jobs/part_source.hpp"
#include "cncstream/jobs/stock_spec.hpp"

namespace cncstream::jobs {

// Raster: rows over the whole part. Steep and shallow: rows where the
// surface is gentler than the steep angle, waterlines (constant-Z contours)
// where it is steeper, with a small overlap.
enum class FinishStrategy { Raster, SteepShallow };

// The band the finishing path may ride above the exact CL (never below it),
// mm. 0.01 mm is below what wood's grain and fuzz show and a tenth of a
// router's runout, and it lets a 3.175 mm ball take moves of sqrt(8 R T) =
// 0.36 mm over convex stretches: a 115,200-baud link then delivers the
// densest stretches above 5,000 mm/min (0.002 mm: 0.16 mm moves, about
// 2,500 mm/min). docs/toolpath.md, "Tolerance".
inline constexpr double kDefaultTolerance = 0.01;

struct ToolpathParams {
  PartSource part;
  cam::Cutter cutter;
  double stepover = 0.4;
  double step = 0;  // along a row; 0: min(stepover / 4, 0.1)
  cam::RasterDirection direction = cam::RasterDirection::X;
  FinishStrategy strategy = FinishStrategy::Raster;
  double steep_angle = 45;  // degrees from the horizontal
  // Set: the scallop height to keep (mm): the row stepover and the waterline
  // step follow from it, the cutter's corner radius and the steep angle
  // (stepover and step are then ignored). A ball or bull-nose cutter only.
  std::optional<double> scallop;
  double feed = 1000, plunge_feed = 300;  // mm/min
  double rpm = 18000;                     // 0: no spindle commands
  std::optional<double> safe_z;           // work coordinates; default 5 mm above the part's top
  double tolerance = kDefaultTolerance;   // the path stays within this above the CL, mm
  // Arcs (G2/G3 in the rows' upright planes) where they fit within the
  // tolerance, less the controller's own arc tolerance (GRBL $12), which its
  // chords take.
  bool arcs = true;
  double controller_arc_tolerance = 0.002;  // mm
  // The link the program will stream over: where a stretch of moves cannot
  // arrive in time at its feed, F is lowered there (gcode/link_feed_limit.hpp).
  // Unset or unbounded: the feeds stay as commanded.
  std::optional<gcode::StreamLink> link;
  std::optional<cam::XYBounds> bounds;         // of the tool tip, model coordinates; default: part box grown by the radius
  std::optional<double> floor;            // lowest tip height, model coordinates; default: the part's lowest z
  XYOrigin origin = XYOrigin::PartMin;
  ZZero z_zero = ZZero::PartTop;
  // Depth of cut. With a stock, no pass of the program removes more than a
  // cutter's maximum depth: where the finishing pass alone would, the job
  // roughs first (Z-level, with `rough`, else the finishing cutter) and the
  // program holds both operations, a tool change between them when the
  // cutters differ. The finishing pass is then measured against the stock
  // the roughing leaves; where the roughing cutter could not reach deep
  // enough (gaps narrower than it), a rest roughing with the finishing
  // cutter comes between them, no tool change before the finishing. Without one (the default here; the CLI's and the
  // daemon's default is `auto`), the finishing pass runs alone from the
  // part's top.
  std::optional<StockSpec> stock;
  std::optional<double> max_depth;        // the finishing cutter's; default: default_max_depth(cutter)
  std::optional<cam::Cutter> rough;            // roughing cutter
  std::optional<double> rough_max_depth;  // the roughing cutter's; default: default_max_depth(rough)
  double leave = 0.3;                     // mm of stock the roughing leaves on the part
  std::optional<double> step_down;        // default: the largest that keeps every pass within both depths
  double rough_stepover = 0;              // mm; 0: 40 % of the roughing cutter's diameter
  std::optional<double> rough_feed;       // mm/min; default: feed
  std::optional<double> rough_rpm;        // the roughing's spindle speed; default: rpm
  // Rest machining after the finishing: a smaller cutter, only where the
  // finishing cutter cannot reach the part (grooves, gaps and inside
  // corners narrower than it), with a tool change before it.
  std::optional<cam::Cutter> rest;
  std::optional<double> rest_feed, rest_rpm;  // the rest machining's; default: feed, rpm
  // The tool library's numbers of the finishing, roughing and rest cutters:
  // the program's T words (OperationSummary::tool). Unset: a cutter given as
  // a spec, numbered by the operations' order and moved past every library
  // number of the same program (job_tool_numbers).
  std::optional<int> tool_number, rough_tool_number, rest_tool_number;
  ToolChangeCode tool_change = ToolChangeCode::PauseM0;
  // Set: the raster finishing's CL grids come from here instead of the exact
  // engine (the CLI's --engine gl: the depth buffer), and `grid_note` (asked
  // after them) says so in the program's header. Raster finishing only:
  // steep-and-shallow and rest machining work from exact point queries.
  std::function<cam::ClGrid(const geometry::Mesh&, const cam::Cutter&, const cam::GridSpec&)> raster_grid;
  std::function<std::string()> grid_note;
  // Not empty: the program is written there (whole or not at all) as the
  // job's last stage.
  std::filesystem::path output;
};

// The band the rows' lines take: the whole tolerance without arcs; with
// arcs half of it, the arcs fitted over those lines taking up to the
// tolerance more (the sum stays within 1.5 T of the CL). A polyline fitted
// in the whole band circumscribes a curve so tightly that no arc, cut in
// the controller's chords, fits over it within the tolerance.
inline double rows_tolerance(const ToolpathParams& p) { return p.arcs ? p.tolerance / 2 : p.tolerance; }

// One operation of the program, for the plan shown before cutting.
struct OperationSummary {
  std::string name;  // "roughing", "rest roughing", "finishing", "rest machining"
  int tool = 1;
  cam::Cutter cutter;
  std::string detail;      // levels, stepover ... in words
  std::size_t first_line = 1;  // of the program (1-based): its tool change or first line
  std::size_t lines = 0;       // of the program's lines, those of this operation
  double cut_length = 0;   // mm at feed
  double feed_time_s = 0;  // cut length / feed
  double max_depth = 0;    // the deepest any pass of it may cut, mm
  // The job's depth-of-cut rule for one move of the program (with a stock;
  // 0 without): the roughing's and the rest operations' max_depth; the
  // finishing's its cutter's maximum depth plus the path tolerance. The
  // finishing's path is checked against that depth, and the program follows
  // the path within the tolerance (lines merged within it, arcs fitted over
  // them): a move may dip that much below the checked path.
  double depth_limit = 0;
  // With a link (ToolpathParams::link): the feed its densest stretch streams
  // at (mm/min; infinite: any) and the share of its feed-move length that
  // now runs below the commanded feed.
  double rpm = 0, feed = 0;  // the operation's spindle speed and cutting feed (mm/min)
  bool link_checked = false;
  double wire_feed = 0;
  double share_below_feed = 0;
};

// The default maximum depth of cut of a cutter: half its diameter for a
// ball or bull-nose, a quarter for a flat end mill.
double default_max_depth(const cam::Cutter& cutter);

struct ToolpathProgram {
  std::string gcode;
  ProgramStats stats;
  cam::RasterPath path;
  // What the finishing operation cuts, in order (the program retracts
  // between pieces): the raster as one piece, or the waterlines then the
  // raster with its steep stretches bridged.
  std::vector<cam::Polyline> finish_pieces;
  std::size_t waterline_pieces = 0;  // the first pieces of finish_pieces
  std::size_t waterline_levels = 0;
  double waterline_step = 0;         // mm between levels (the closest two)
  double waterline_step_max = 0;     // mm between the farthest two (spaced by the walls: wider on steeper ones)
  std::size_t steep_bridges = 0;     // raster stretches left to the waterlines
  cam::Cutter cutter;
  std::size_t facets = 0;
  geometry::Vec3 work_offset;  // model -> work coordinates
  geometry::Mesh work_mesh;    // the part placed in work coordinates (for a verify)
  // The CL grid the rows were sampled from, resampled small (at most
  // kPreviewSideMax nodes a side) in work coordinates, for a preview; the
  // full grid is not kept (path.grid is empty).
  HeightPreview preview;
  // In program order; one (finishing) without a stock.
  std::vector<OperationSummary> operations;
  std::optional<geometry::Box3> stock;  // work coordinates, when the job had one
  // What the plan decided and why ("the finishing pass would cut 11.5 mm in
  // one pass, more than ... : roughing first").
  std::vector<std::string> notes;
  // Each stage's own wall time. The rest machining and a roughing asked for
  // (p.rough) run beside the finishing's CL + path: then the times overlap
  // (stages_overlap) and add up to more than the whole.
  double seconds_load = 0, seconds_path = 0, seconds_rough = 0, seconds_rest = 0, seconds_gcode = 0;
  bool stages_overlap = false;
};

// The rows' spacing in words: "0.4" for even rows, "0.457 to 0.797" for
// rows spaced by the slope across them.
std::string row_spacing_text(const cam::RasterPath& path);

// Stages: "load", "tool path", "rest machining" (with a rest cutter),
// "roughing" (with a stock), "G-code", "write" (with an output), "done".
// Throws Cancelled on a stop request.
ToolpathProgram generate_toolpath(const ToolpathParams& params, const JobControl& control = {});

}  // namespace cncstream::jobs
