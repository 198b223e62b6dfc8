#include "cncsim/removal.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cncstream/cam/height_field_io.hpp"

namespace cncsim {

using cncstream::Vec3;

StockBox parse_stock_box(const std::string& text, double resolution) {
  Vec3 a, b;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf:%lf,%lf,%lf%c", &a.x, &a.y, &a.z, &b.x, &b.y, &b.z, &tail) != 6)
    throw std::invalid_argument("--stock '" + text + "': expected X0,Y0,Z0:X1,Y1,Z1 (mm, machine coordinates)");
  StockBox box{min(a, b), max(a, b), resolution};
  const Vec3 size = box.hi - box.lo;
  if (size.x <= 0 || size.y <= 0 || size.z <= 0)
    throw std::invalid_argument("--stock '" + text + "': the box has no volume");
  if (!(resolution > 0)) throw std::invalid_argument("--resolution must be positive");
  return box;
}

StockBox stock_box_for(const cncstream::Mesh& design, double resolution) {
  const cncstream::Box3 b = design.bounds();
  if (b.empty()) throw std::invalid_argument("the design mesh is empty");
  return {b.lo, b.hi, resolution};
}

MaterialRemoval::MaterialRemoval(const StockBox& box, const cncstream::Cutter& cutter)
    : stock_(cncstream::GridSpec::covering(box.lo.x, box.lo.y, box.hi.x, box.hi.y, box.resolution, box.resolution),
             box.hi.z),
      cutter_(cutter),
      bottom_(box.lo.z) {}

void MaterialRemoval::attach(Machine& machine) {
  machine.set_motion_observer([this](const Vec3& a, const Vec3& b, bool) { cut(a, b); });
}

void MaterialRemoval::cut(const Vec3& from, const Vec3& to) {
  // Moves entirely above the stock top cannot touch it: skip the sweep.
  if (std::min(from.z, to.z) >= stock_.top()) return;
  stock_.cut_segment(from, to, cutter_);
  ++segments_;
}

void MaterialRemoval::write_result(const std::filesystem::path& path) const {
  cncstream::write_height_field(path, stock_.grid(), stock_.heights());
}

cncstream::HeightFieldStock stock_from_heights(const cncstream::GridSpec& grid, const std::vector<float>& heights) {
  if (heights.size() != grid.size()) throw std::invalid_argument("height field size does not match its grid");
  double top = -HUGE_VAL;
  for (float z : heights)
    if (std::isfinite(z)) top = std::max(top, static_cast<double>(z));
  if (!std::isfinite(top)) throw std::invalid_argument("height field has no values");
  return cncstream::HeightFieldStock(grid, top, std::vector<double>(heights.begin(), heights.end()));
}

}  // namespace cncsim
