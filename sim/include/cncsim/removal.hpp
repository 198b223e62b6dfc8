#pragma once
// Material removal for the simulator: a height-field stock block (machine
// coordinates) cut by every piece of tool motion with the exact swept cutter.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <map>
#include <set>
#include <string>

#include "cncsim/machine.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/cam/stock.hpp"
#include "cncstream/geometry/mesh.hpp"

namespace cncsim {

struct StockBox {
  cncstream::geometry::Vec3 lo, hi;  // machine coordinates; the top is hi.z
  double resolution = 0.1;  // grid step, mm
};

// "X0,Y0,Z0:X1,Y1,Z1" (corners in any order). Throws std::invalid_argument
// naming the text.
StockBox parse_stock_box(const std::string& text, double resolution);
// The XY bounding box of a design with its top at the design's highest point.
StockBox stock_box_for(const cncstream::geometry::Mesh& design, double resolution);

// Tool number -> cutter. `text` is "1=ball:3.175,2=bull:3.175:0.79" or the
// path of a file with one "N=SPEC" per line ('#' starts a comment). Errors
// name the entry (and the file and line).
// An entry may give the tool's stick-out: "2=ball:3.175@37.3" (mm).
using ToolTable = std::map<int, cncstream::cam::Cutter>;
ToolTable parse_tool_table(const std::string& text);
// The stick-outs of the same text (empty when it gives none; all or none).
using StickOuts = std::map<int, double>;
StickOuts parse_tool_stick_outs(const std::string& text);

class MaterialRemoval {
 public:
  MaterialRemoval(const StockBox& box, const cncstream::cam::Cutter& cutter);
  // Goes on cutting a stock an earlier run left (stock_from_heights of its result).
  MaterialRemoval(cncstream::cam::HeightFieldStock stock, const cncstream::cam::Cutter& cutter);

  // Routes the machine's motion into the stock (replaces its observers); a
  // T word then switches to that tool of the table, once the motion queued
  // before it has run.
  void attach(Machine& machine);
  void set_tool_table(ToolTable table) { tools_ = std::move(table); }
  // T numbers selected that the table does not hold (the cutter was kept).
  const std::set<int>& unknown_tools() const { return unknown_tools_; }
  void cut(const cncstream::geometry::Vec3& from, const cncstream::geometry::Vec3& to);

  const cncstream::cam::HeightFieldStock& stock() const { return stock_; }
  const cncstream::cam::Cutter& cutter() const { return cutter_; }
  // A tool change: later moves cut with this cutter.
  void set_cutter(const cncstream::cam::Cutter& cutter) { cutter_ = cutter; }
  std::size_t segments() const { return segments_; }
  // The deepest any one move cut (the largest height drop of a node in one
  // straight piece of motion), per tool number selected when it ran (0
  // before any T word): the depth of cut a program asks of each cutter.
  const std::map<int, double>& deepest_cut_by_tool() const { return deepest_; }

  // Writes the machined surface as a height field (<path> + <path>.txt) and
  // as a closed STL solid down to the stock's bottom (<path> with .stl).
  // `work_offset`: where the part's model sat in the machine's coordinates
  // (work = model + offset), recorded in the sidecar when known.
  // `work_origin`: the machine coordinates of work zero (G5x + G92): the
  // surface is written in work coordinates (machine − origin) and the origin
  // recorded, so a later setup places it; nullopt: machine coordinates, no
  // origin recorded. Returns the STL's path.
  std::filesystem::path write_result(const std::filesystem::path& path,
                                     std::optional<cncstream::geometry::Vec3> work_offset = std::nullopt,
                                     std::optional<cncstream::geometry::Vec3> work_origin = std::nullopt) const;

 private:
  cncstream::cam::HeightFieldStock stock_;
  cncstream::cam::Cutter cutter_;
  double bottom_;
  std::size_t segments_ = 0;
  ToolTable tools_;
  std::set<int> unknown_tools_;
  int tool_ = 0;
  std::map<int, double> deepest_;
};

// Rebuilds a stock whose surface equals `heights` (a result file read back):
// each node is lowered by a plunge of a flat cutter narrower than the grid.
cncstream::cam::HeightFieldStock stock_from_heights(const cncstream::cam::GridSpec& grid, const std::vector<float>& heights);

}  // namespace cncsim
