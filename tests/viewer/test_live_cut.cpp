// The live job's removed material: a job program's own comments give the
// stock and each operation's cutter; the moves before the executing one are
// cut, in slices or at once alike, and a known slot has its known volume.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cncstream/viewer/live_cut.hpp"
#include "support/slot_program.hpp"

using namespace cncstream;
using namespace cncstream::viewer;

namespace {

std::size_t segment_after_line(const Toolpath& p, std::uint32_t line0) {
  std::size_t k = 0;
  while (k < p.size() && p.segments[k].line <= line0) ++k;
  return k;
}

}  // namespace

TEST(LiveCut, AJobProgramNamesItsStockAndEachOperationsCutter) {
  const auto stock = program_stock(testparts::kSlotProgram);
  ASSERT_TRUE(stock);
  EXPECT_EQ(stock->lo.x, 0);
  EXPECT_EQ(stock->hi.x, 30);
  EXPECT_EQ(stock->lo.y, 0);
  EXPECT_EQ(stock->hi.y, 20);
  EXPECT_EQ(stock->lo.z, -5);
  EXPECT_EQ(stock->hi.z, 0);
  const auto cutters = program_cutters(testparts::kSlotProgram);
  ASSERT_EQ(cutters.size(), 2u);
  EXPECT_EQ(cutters[0].line, 3u);  // its comment (0-based): the first tool needs no change
  EXPECT_EQ(cutters[0].cutter.type, cam::CutterType::Flat);
  EXPECT_EQ(cutters[0].cutter.radius, 3);
  EXPECT_EQ(cutters[1].line, 15u);  // from its M0 on
  EXPECT_EQ(cutters[1].cutter.type, cam::CutterType::Ball);
  EXPECT_EQ(cutters[1].cutter.radius, 1);
  // Another program says neither.
  EXPECT_FALSE(program_stock("G0 X1\n(stock: X 1..0 Y 0..1 Z 0..1)\n"));
  EXPECT_TRUE(program_cutters("G0 X1\nG1 X2 F100\n").empty());
}

TEST(LiveCut, OnlyTheExecutedMovesAreCutAndTheSlotHasItsVolume) {
  const Toolpath path = build_toolpath(testparts::kSlotProgram);
  LiveCut cut(path, program_cutters(testparts::kSlotProgram), program_stock(testparts::kSlotProgram));
  EXPECT_EQ(cut.grid().x0, 0);
  EXPECT_LE(cut.grid().size(), LiveCutOptions{}.max_nodes);
  EXPECT_EQ(cut.advance(0), 0u);
  EXPECT_EQ(cut.removed_volume(), 0);

  // Up to the plunge (line 8, 0-based): a 6 mm hole 2 mm deep.
  cut.advance(static_cast<double>(segment_after_line(path, 8)));
  const double hole = std::numbers::pi * 9 * 2;
  EXPECT_NEAR(cut.removed_volume(), hole, 0.03 * hole);
  // A position behind changes nothing.
  const double before = cut.removed_volume();
  EXPECT_EQ(cut.advance(1), 0u);
  EXPECT_EQ(cut.removed_volume(), before);
  EXPECT_EQ(cut.cutter_in_spindle().type, cam::CutterType::Flat);

  // The whole program: the slot, and the ball after the tool change removes nothing above the stock.
  cut.advance(static_cast<double>(path.size()));
  EXPECT_EQ(cut.segments_cut(), path.size());
  const double slot = (10 * 6 + std::numbers::pi * 9) * 2;
  EXPECT_NEAR(cut.removed_volume(), slot, 0.02 * slot);
  EXPECT_EQ(cut.cutter_in_spindle().type, cam::CutterType::Ball);
  // The slot's floor is at Z-2, the stock beside it untouched.
  const auto h = cut.heights();
  const cam::GridSpec& g = cut.grid();
  auto at = [&](double x, double y) {
    const auto i = static_cast<std::size_t>(std::lround((x - g.x0) / g.dx));
    const auto j = static_cast<std::size_t>(std::lround((y - g.y0) / g.dy));
    return h[j * g.nx + i];
  };
  EXPECT_NEAR(at(15, 10), -2, 1e-6);
  EXPECT_NEAR(at(15, 12.9), -2, 1e-6);
  EXPECT_NEAR(at(15, 13.5), 0, 1e-6);
  EXPECT_NEAR(at(25, 10), 0, 1e-6);
}

TEST(LiveCut, CuttingInSlicesEqualsCuttingAtOnce) {
  const Toolpath path = build_toolpath(testparts::kSlotProgram);
  LiveCut once(path, program_cutters(testparts::kSlotProgram), program_stock(testparts::kSlotProgram));
  LiveCut sliced(path, program_cutters(testparts::kSlotProgram), program_stock(testparts::kSlotProgram));
  once.advance(static_cast<double>(path.size()));
  while (sliced.advance(static_cast<double>(path.size()), 1) > 0) {
  }
  EXPECT_EQ(sliced.heights(), once.heights());
}

TEST(LiveCut, WithoutAStockItIsTheMovesExtentUpToTheirTop) {
  // A program that names neither stock nor cutter: the cutter comes from the user.
  const Toolpath path = build_toolpath("G21 G90\nG0 Z5\nX0 Y0\nG1 Z-1 F300\nX10 F600\nY10\nG0 Z5\n");
  LiveCut cut(path, {{0, cam::Cutter::flat(2)}});
  // The cutting moves span X 0..10, Y 0..10: grown by the radius. The
  // plunge starts above Z0, so the stock's top is Z0, not the plunge's start.
  EXPECT_NEAR(cut.grid().x0, -1, 1e-9);
  EXPECT_NEAR(cut.grid().y0, -1, 1e-9);
  EXPECT_NEAR(cut.grid().x1(), 11, cut.grid().dx);
  cut.advance(static_cast<double>(path.size()));
  // A 2 mm disc swept along the L, 1 mm deep: 2 x 20 less the corner's overlap, the end caps and the outer corner.
  const double l_slot = 40 - 1 + std::numbers::pi + std::numbers::pi / 4;
  EXPECT_NEAR(cut.removed_volume(), l_slot, 0.03 * l_slot);
  EXPECT_THROW(LiveCut(path, {}), std::invalid_argument);
  const Toolpath rapids_only = build_toolpath("G0 X1 Y1\nG0 X2\n");
  EXPECT_THROW(LiveCut(rapids_only, {{0, cam::Cutter::flat(2)}}), std::invalid_argument);
}
