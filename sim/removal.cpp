#include "cncsim/removal.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "cncsim/number_text.hpp"
#include "cncsim/output_file.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/height_field_mesh.hpp"

namespace cncsim {

using cncstream::geometry::Vec3;

StockBox parse_stock_box(const std::string& text, double resolution) {
  const auto colon = text.find(':');
  const auto a = colon == std::string::npos ? std::nullopt : vec3_from(std::string_view(text).substr(0, colon));
  const auto b = colon == std::string::npos ? std::nullopt : vec3_from(std::string_view(text).substr(colon + 1));
  if (!a || !b)
    throw std::invalid_argument("--stock '" + text + "': expected X0,Y0,Z0:X1,Y1,Z1 (mm, machine coordinates)");
  StockBox box{min(*a, *b), max(*a, *b), resolution};
  const Vec3 size = box.hi - box.lo;
  if (size.x <= 0 || size.y <= 0 || size.z <= 0)
    throw std::invalid_argument("--stock '" + text + "': the box has no volume");
  if (!(resolution > 0)) throw std::invalid_argument("--resolution must be positive");
  return box;
}

StockBox stock_box_for(const cncstream::geometry::Mesh& design, double resolution) {
  const cncstream::geometry::Box3 b = design.bounds();
  if (b.empty()) throw std::invalid_argument("the design mesh is empty");
  return {b.lo, b.hi, resolution};
}

MaterialRemoval::MaterialRemoval(const StockBox& box, const cncstream::cam::Cutter& cutter)
    : stock_(cncstream::cam::GridSpec::covering(box.lo.x, box.lo.y, box.hi.x, box.hi.y, box.resolution, box.resolution),
             box.hi.z),
      cutter_(cutter),
      bottom_(box.lo.z) {}

MaterialRemoval::MaterialRemoval(cncstream::cam::HeightFieldStock stock, const cncstream::cam::Cutter& cutter)
    : stock_(std::move(stock)), cutter_(cutter), bottom_(stock_.top()) {
  for (double z : stock_.heights()) bottom_ = std::min(bottom_, z - 1.0);
}

namespace {

// Both tables from one text: cutters, and stick-outs where an entry has "@L".
std::pair<ToolTable, StickOuts> parse_tool_entries(const std::string& text) {
  ToolTable table;
  StickOuts lengths;
  auto trim = [](const std::string& s) {
    const auto first = s.find_first_not_of(" \t\r");
    return first == std::string::npos ? std::string() : s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
  };
  auto add = [&](std::string entry, const std::string& where) {
    const auto hash = entry.find('#');
    if (hash != std::string::npos) entry.erase(hash);
    entry = trim(entry);
    if (entry.empty()) return;
    const auto eq = entry.find('=');
    const auto number = eq == std::string::npos ? std::nullopt : number_from<int>(entry.substr(0, eq));
    if (!number || *number < 0)
      throw std::invalid_argument(where + "'" + entry + "': expected N=SPEC, e.g. 1=ball:3.175");
    const int tool = *number;
    std::string spec = trim(entry.substr(eq + 1));
    if (const auto at = spec.find('@'); at != std::string::npos) {
      const auto length = number_from<double>(spec.substr(at + 1));
      if (!length || !(*length > 0) || !std::isfinite(*length))
        throw std::invalid_argument(where + "tool " + std::to_string(tool) + " '" + spec +
                                    "': expected SPEC@STICKOUT, the stick-out a positive length in mm (e.g. flat:6@30)");
      lengths[tool] = *length;
      spec = trim(spec.substr(0, at));
    }
    try {
      table[tool] = cncstream::cam::parse_cutter_spec(spec);
    } catch (const std::exception& e) {
      throw std::invalid_argument(where + "tool " + std::to_string(tool) + ": " + e.what());
    }
  };
  std::error_code ec;
  if (std::filesystem::is_regular_file(text, ec)) {
    std::ifstream in(text);
    if (!in) throw std::invalid_argument("tool table " + text + ": cannot read it");
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) add(line, "tool table " + text + " line " + std::to_string(n) + ": ");
  } else {
    std::size_t at = 0;
    while (at <= text.size()) {
      const auto comma = std::min(text.find(',', at), text.size());
      add(text.substr(at, comma - at), "tool table entry ");
      at = comma + 1;
    }
  }
  if (table.empty()) throw std::invalid_argument("tool table '" + text + "' holds no tools");
  // Lengths for some tools only would leave the others' tips unknown.
  if (!lengths.empty())
    for (const auto& [tool, cutter] : table)
      if (!lengths.contains(tool))
        throw std::invalid_argument("tool table '" + text + "': tool " + std::to_string(tool) +
                                    " has no stick-out (@mm) while others have one: give every tool's or none");
  return {std::move(table), std::move(lengths)};
}

}  // namespace

ToolTable parse_tool_table(const std::string& text) { return parse_tool_entries(text).first; }
StickOuts parse_tool_stick_outs(const std::string& text) { return parse_tool_entries(text).second; }

void MaterialRemoval::attach(Machine& machine) {
  machine.set_motion_observer([this](const Vec3& a, const Vec3& b, bool) { cut(a, b); });
  machine.set_tool_observer([this](int tool) {
    tool_ = tool;
    if (tools_.empty()) return;  // one cutter for the whole run
    if (const auto it = tools_.find(tool); it != tools_.end()) cutter_ = it->second;
    else unknown_tools_.insert(tool);
  });
}

void MaterialRemoval::cut(const Vec3& from, const Vec3& to) {
  // Moves entirely above the stock top cannot touch it: skip the sweep.
  if (std::min(from.z, to.z) >= stock_.top()) return;
  stock_.cut_segment(from, to, cutter_);
  ++segments_;
  double& deepest = deepest_[tool_];
  deepest = std::max(deepest, stock_.last_max_depth());
}

std::filesystem::path MaterialRemoval::write_result(const std::filesystem::path& path,
                                                   std::optional<cncstream::geometry::Vec3> work_offset,
                                                   std::optional<cncstream::geometry::Vec3> work_origin) const {
  // In work coordinates when the work zero is known: machine − origin.
  cncstream::cam::GridSpec grid = stock_.grid();
  std::vector<double> heights = stock_.heights();
  if (work_origin) {
    grid.x0 -= work_origin->x;
    grid.y0 -= work_origin->y;
    for (double& z : heights) z -= work_origin->z;
  }
  // Each file whole or not at all; the sidecar is in place before its data file.
  write_whole(path, [&](const std::filesystem::path& file) {
    cncstream::cam::write_height_field(file, grid, heights, work_offset, work_origin);
    std::filesystem::rename(cncstream::cam::height_field_sidecar(file), cncstream::cam::height_field_sidecar(path));
  });
  auto stl = path;
  stl.replace_extension(".stl");
  // A cut through the stock's bottom still gives a closed solid.
  double bottom = bottom_;
  for (double z : stock_.heights()) bottom = std::min(bottom, z - 1.0);
  write_whole(stl, [&](const std::filesystem::path& file) {
    cncstream::cam::write_height_field_stl(file, grid, heights, bottom - (work_origin ? work_origin->z : 0.0));
  });
  return stl;
}

cncstream::cam::HeightFieldStock stock_from_heights(const cncstream::cam::GridSpec& grid, const std::vector<float>& heights) {
  if (heights.size() != grid.size()) throw std::invalid_argument("height field size does not match its grid");
  double top = -HUGE_VAL;
  for (float z : heights)
    if (std::isfinite(z)) top = std::max(top, static_cast<double>(z));
  if (!std::isfinite(top)) throw std::invalid_argument("height field has no values");
  return cncstream::cam::HeightFieldStock(grid, top, std::vector<double>(heights.begin(), heights.end()));
}

}  // namespace cncsim
