#pragma once
// A G-code program as the viewer's line buffer, pure (no GL): every move the
// project's interpreter sees (so modal state, offsets and errors are the
// firmware's), arcs as chords whose end points lie on the arc, rapids
// flagged, the feed and the operation of every segment kept. Nothing is
// thinned: the renderer draws every segment, the timeline walks them all.
//
// Positions are work coordinates (machine - the work offset in force) plus
// ToolpathOptions::offset, as floats: the GPU's format, and 5 million
// segments fit in 100 MB (one line strip).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/geometry/vec3.hpp"
#include "cncstream/image/image.hpp"

namespace cncstream::viewer {

// A point of the path as the GPU reads it (20 bytes). The path is one line
// strip: segment k runs from vertex segments[k].vertex - 1 to
// segments[k].vertex, and that end vertex carries the segment's colour and
// kind (GL's provoking vertex for flat attributes). A jump between
// segments that do not meet (a work offset changed) is a hidden line.
struct PathVertex {
  float x = 0, y = 0, z = 0;
  float along = 0;   // mm along a run of rapids (the dash pattern); 0 elsewhere
  std::uint8_t r = 0, g = 0, b = 0;
  std::uint8_t kind = 0;  // of the line ending here: kCut, kRapid, kJump
};
inline constexpr std::uint8_t kCut = 0, kJump = 128, kRapid = 255;  // normalised bytes: 0, 0.5, 1

struct SegmentInfo {
  float feed = 0;               // mm/min; 0 for rapids
  std::uint32_t line = 0;       // 0-based line of the program
  std::uint32_t operation = 0;  // index into Toolpath::operations
  std::uint32_t vertex = 0;     // the end vertex
};

struct ToolpathError {
  std::size_t line = 0;  // 0-based
  int status = 0;        // GRBL error code
};

struct Toolpath {
  std::vector<PathVertex> vertices;  // the strip
  std::vector<SegmentInfo> segments;
  std::vector<std::string> operations;  // names; an unnamed one is "operation N"
  std::vector<ToolpathError> errors;
  std::size_t lines = 0, rapids = 0, arcs = 0;
  geometry::Box3 bounds;                         // of every vertex
  double min_feed = 0, max_feed = 0;   // over the cutting segments

  std::size_t size() const { return segments.size(); }
  geometry::Vec3 from(std::size_t k) const { return at(segments[k].vertex - 1); }
  geometry::Vec3 to(std::size_t k) const { return at(segments[k].vertex); }
  bool rapid(std::size_t k) const { return vertices[segments[k].vertex].kind == kRapid; }
  // The point at timeline position t in [0, size()]: segment floor(t), the
  // fraction of it done.
  geometry::Vec3 point_at(double t) const;
  // The strip's vertices before which the segments done at timeline t end
  // (the renderer draws lines whose end vertex is below it bright).
  std::uint32_t vertices_done(double t) const;

 private:
  geometry::Vec3 at(std::size_t v) const { return {vertices[v].x, vertices[v].y, vertices[v].z}; }
};

struct ToolpathOptions {
  double arc_tolerance = 0.002;  // chord error of arcs, mm ($12's default)
  geometry::Vec3 offset{};                 // added to every point (work -> the part's frame)
  gcode::ParserState initial;
};

// An operation begins at the first move, at every tool change (a T word that
// changes the tool) and at a comment-only line after moves (CAM programs name
// the next operation so: "(Finishing)"). Lines with errors are recorded and
// skipped as the firmware would skip them. Colours: by_feed.
Toolpath build_toolpath(std::string_view program, const ToolpathOptions& options = {});

// Appends one segment (used by build_toolpath and for synthetic paths).
void append_segment(Toolpath& path, const geometry::Vec3& from, const geometry::Vec3& to, bool rapid, double feed,
                    std::uint32_t line, std::uint32_t operation);

enum class PathColouring { Feed, Operation };
PathColouring parse_path_colouring(const std::string& name);  // "feed" | "operation"
// Cutting segments: by feed on the viridis ramp from the slowest to the
// fastest, or by operation (category_colour); rapids orange.
void colour_toolpath(Toolpath& path, PathColouring how);
inline constexpr image::Rgb kRapidColour{255, 140, 0};

// The strip for drawing at a distance: indices of the vertices kept, where
// the dropped ones lie within `tolerance` (mm) of the line that replaces
// them and every merged line has one kind and colour. Drawn when a pixel is
// at least twice the tolerance, it looks the same as the whole strip; the
// index values are the vertices' own, so the timeline still applies.
std::vector<std::uint32_t> display_strip(const Toolpath& path, double tolerance);

}  // namespace cncstream::viewer
