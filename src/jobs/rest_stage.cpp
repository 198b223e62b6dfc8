#include "rest_stage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "cncstream/cam/cleanup.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/pass_depth.hpp"
#include "cncstream/cam/pencil.hpp"
#include "cncstream/cam/reach.hpp"
#include "cncstream/cam/stock.hpp"
#include "finishing_stage.hpp"
#include "roughing_stage.hpp"

namespace cncstream::jobs {

namespace {

// The skin the rest cutter's Z-levels leave for its rows (as the rest
// roughing before the finishing leaves one for the finishing).
constexpr double kRestLevelLeave = 0.05;

}  // namespace

RestStage plan_rest(const ToolpathParams& p, const geometry::Mesh& mesh, const cam::ClEngine& finish_engine, const cam::XYBounds& region,
                    const cam::XYLattice& lattice, const cam::Checkpoint& checkpoint) {
  const cam::Cutter& big = p.cutter;
  RestStage s;
  s.cutter = *p.rest;
  const cam::Cutter& small = s.cutter;
  if (!(small.radius < big.radius - 1e-9))
    throw std::invalid_argument(fmt::format("the rest cutter {} must be smaller than the finishing cutter {}: it cuts "
                                            "where that one cannot reach",
                                            small.spec(), big.spec()));
  // Where the finishing cutter leaves material: its reach limit over the
  // part on a grid fine enough for the smaller cutter's grooves.
  const double h = std::clamp(small.radius / 2, 0.05, 0.25);
  const cam::GridSpec grid = cam::GridSpec::covering(region.x0, region.y0, region.x1, region.y1, h, h);
  const cam::DesignHeights design = cam::design_heights(mesh, grid);
  std::vector<std::uint8_t> wanted(grid.size());
  for (std::size_t k = 0; k < grid.size(); ++k) wanted[k] = design.off_part[k] ? 0 : 1;
  const double pitch = std::min(h, 0.1);
  const double r = big.radius;
  const cam::GridSpec lattice_around =
      cam::reach_lattice(grid, region.x0 - r, region.y0 - r, region.x1 + r, region.y1 + r, pitch, pitch);
  const cam::ClGrid dense = finish_engine.compute(lattice_around, cam::checkpoint_part(checkpoint, 0, 0.3));
  const std::vector<double> reach = cam::reach_heights(dense, big, grid, wanted, cam::checkpoint_part(checkpoint, 0.3, 0.5));
  std::vector<double> left(grid.size(), std::numeric_limits<double>::quiet_NaN());
  // The reach lattice's own scallop and a micron-scale CL are not rest.
  s.threshold = std::max(2 * p.tolerance, 0.01);
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  for (std::size_t j = 0; j < grid.ny; ++j)
    for (std::size_t i = 0; i < grid.nx; ++i) {
      const std::size_t k = j * grid.nx + i;
      if (!wanted[k] || !std::isfinite(reach[k])) continue;
      left[k] = reach[k] - design.z[k];
      if (!(left[k] > s.threshold)) continue;
      ++s.nodes;
      x0 = std::min(x0, grid.x(i));
      x1 = std::max(x1, grid.x(i));
      y0 = std::min(y0, grid.y(j));
      y1 = std::max(y1, grid.y(j));
      if (left[k] > s.most_left) {
        s.most_left = left[k];
        s.most_left_at = {grid.x(i), grid.y(j), design.z[k]};
      }
    }
  // Its rows: spaced as the finishing's would be for its own radius (the
  // scallop's spacing), or the stepover scaled by the radii.
  if (p.scallop && small.corner_radius > 0) {
    ToolpathParams own = p;
    own.cutter = small;
    s.stepover = finish_spacing(own).stepover;
  } else {
    s.stepover = p.stepover * small.radius / big.radius;
  }
  if (s.nodes == 0) return s;

  cam::ClOptions clo;
  clo.floor = p.floor;
  clo.floor_is_lowest = true;  // as the finishing's engine
  const cam::ClEngine engine(mesh, small, clo);
  const double grow = small.radius + h;
  cam::XYBounds box{std::max(region.x0, x0 - grow), std::max(region.y0, y0 - grow), std::min(region.x1, x1 + grow),
               std::min(region.y1, y1 + grow)};
  cam::RasterOptions ro;
  ro.stepover = s.stepover;
  ro.step = std::min(s.stepover / 4, 0.1);
  ro.direction = p.direction;
  ro.tolerance = rows_tolerance(p);
  ro.lattice = lattice;
  const cam::RasterPath rows = cam::build_raster(engine, box, ro, cam::checkpoint_part(checkpoint, 0.5, 0.7));
  s.pieces = cam::cleanup_pieces(rows, grid, left, s.threshold, grow, p.direction != cam::RasterDirection::Y);
  // Then along the creases there (a groove's bottom, where it touches both
  // faces): the rows leave their cusps right at a crease.
  cam::PencilOptions po;
  po.step = std::min(0.1, small.radius / 4);
  po.lattice = lattice;
  po.tolerance = p.tolerance;
  auto where = [&](double x, double y) {
    const double fi = std::round((x - grid.x0) / grid.dx), fj = std::round((y - grid.y0) / grid.dy);
    if (fi < 0 || fj < 0 || fi >= double(grid.nx) || fj >= double(grid.ny)) return false;
    const double v = left[static_cast<std::size_t>(fj) * grid.nx + static_cast<std::size_t>(fi)];
    return std::isfinite(v) && v > s.threshold;
  };
  for (cam::Polyline& pl : cam::pencil_passes(engine, box, po, where)) {
    s.pieces.push_back(std::move(pl));
    ++s.pencils;
  }

  // The stock the finishing leaves: its reach limit, its cusps on top (on
  // the part; the reach elsewhere).
  const double cusp = p.scallop ? *p.scallop
                                : big.corner_radius > 0 ? p.stepover * p.stepover / (8 * big.corner_radius) : 0;
  double top = -HUGE_VAL;
  std::vector<double> z(grid.size());
  for (std::size_t k = 0; k < grid.size(); ++k) {
    z[k] = std::isfinite(reach[k]) ? reach[k] + (wanted[k] ? cusp + p.tolerance : 0) : dense.floor;
    top = std::max(top, z[k]);
  }
  cam::HeightFieldStock stock(grid, top, std::move(z));
  const double most = default_max_depth(small);
  const double retract_z = top + 1;
  cam::RoughingParams rr;
  rr.tolerance = 0.05;
  rr.leave = std::max(kRestLevelLeave, rr.tolerance / 2 + p.tolerance);
  rr.step_down = most - rr.leave;
  // Its rows' side cuts of the skin its Z-levels leave on a wall (the leave
  // and the cusps between levels) are as tall as the wall: a rim that wide
  // is left out of the depth of cut (as the finishing's of the roughing's
  // skin).
  const double half_step = std::min(small.radius, rr.step_down / 2);
  const double rim = rr.leave + small.radius - std::sqrt(small.radius * small.radius - half_step * half_step);
  cam::PassDepth depth = cam::pass_depth(stock, s.pieces, small, rim, most, retract_z);
  if (depth.deepest <= most + 1e-9) {
    s.depth = depth.deepest;
    if (checkpoint) checkpoint(1.0);
    return s;
  }

  // Too deep for one pass: Z-levels of the smaller cutter near the moves
  // too deep, from the stock the finishing leaves, then measured again.
  if (small.corner_radius > 0) rr.stepover = round_stepover(small, rr.step_down);
  rr.near_radius = small.radius;
  rr.bottom = dense.floor;
  s.level_leave = rr.leave;
  const cam::ClEngine grown(mesh, cam::grown_cutter(small, rr.leave), clo);
  cam::StockBlock block{region.x0, region.y0, region.x1, region.y1, top, nullptr};
  double grid_step = 0;
  for (int round = 1;; ++round) {
    rr.near = depth.over;
    rr.grid_step = grid_step;
    block.surface = &stock;
    cam::RoughingPath levels = cam::build_zlevel_roughing(grown, small, block, rr, cam::checkpoint_part(checkpoint, 0.7, 0.95));
    if (levels.levels.empty()) break;
    stock = stock_after(stock, levels);
    grid_step = levels.grid.dx / 2;
    s.levels.push_back(std::move(levels));
    depth = cam::pass_depth(stock, s.pieces, small, rim, most, retract_z);
    if (depth.deepest <= most + 1e-9 || round == 3) break;
  }
  s.depth = depth.deepest;
  if (depth.deepest > most + 1e-9)
    throw std::invalid_argument(fmt::format(
        "the {} leaves up to {:.2f} mm near X{:.3f} Y{:.3f} (model coordinates); after Z-levels of the rest cutter {} "
        "its rows would still cut {:.2f} mm there, more than its {:.2f} mm: choose a rest cutter closer in size",
        big.spec(), s.most_left, depth.at.x, depth.at.y, small.spec(), depth.deepest, most));
  if (checkpoint) checkpoint(1.0);
  return s;
}

}  // namespace cncstream::jobs
