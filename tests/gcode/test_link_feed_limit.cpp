// Lowering F where the link cannot deliver a program's moves in time.
#include <gtest/gtest.h>

#include <fmt/core.h>

#include <cmath>
#include <string>

#include "cncstream/gcode/line_lexer.hpp"
#include "cncstream/gcode/link_feed_limit.hpp"
#include "cncstream/gcode/program.hpp"

namespace {

using namespace cncstream::gcode;

constexpr double kRate = 11520;  // 115,200 baud

LinkFeedOptions serial() {
  LinkFeedOptions o;
  o.link.bytes_per_second = kRate;
  return o;
}

// Moves along X of `step` mm, lines padded to `bytes` with the newline.
void append_moves(std::string& text, double& x, std::size_t count, double step, std::size_t bytes) {
  for (std::size_t i = 0; i < count; ++i) {
    x += step;
    std::string l = fmt::format("X{:.3f}", x);
    while (l.size() + 1 < bytes) l.insert(l.begin() + 1, '0');
    text += l + "\n";
  }
}

// Every window of the program's feed moves, at the feeds it commands: the
// wire's time is never longer than the moves' (the rule the limit applies).
double worst_wire_over_motion(const std::string& text, std::size_t window) {
  const auto trace = trace_program(text);
  const auto lines = split_lines(text);
  std::vector<double> len(lines.size(), 0.0), feed(lines.size(), 0.0);
  for (const auto& s : trace.segments)
    if (!s.rapid) len[s.source_line] += cncstream::geometry::norm(s.to - s.from), feed[s.source_line] = s.feed;
  std::vector<double> wire, motion;
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (len[i] > 0) wire.push_back(grbl_line_cost(lines[i]) / kRate), motion.push_back(len[i] / feed[i] * 60);
  double worst = 0;
  for (std::size_t s = 0; s + window <= wire.size(); ++s) {
    double w = 0, m = 0;
    for (std::size_t k = s; k < s + window; ++k) w += wire[k], m += motion[k];
    worst = std::max(worst, w / m);
  }
  return worst;
}

TEST(LinkFeedLimit, StreamableFeedKnownAnswer) {
  // 25-byte lines of 0.03 mm: 0.03 mm per 25/11520 s = 829.4 mm/min.
  const std::vector<double> len(100, 0.03), bytes(100, 25);
  EXPECT_NEAR(streamable_feed(len, bytes, kRate, 50), 0.03 / (25 / kRate) * 60, 0.01);
  EXPECT_TRUE(std::isinf(streamable_feed(len, bytes, 0, 50)));  // native USB
}

TEST(LinkFeedLimit, DenseStretchGetsALowerFeedAndTheCommandedOneBack) {
  std::string text = "G21G90G94G17\nG0X0Y0Z0\nG1F3000\n";
  double x = 0;
  append_moves(text, x, 100, 2.0, 12);
  append_moves(text, x, 400, 0.03, 25);
  append_moves(text, x, 100, 2.0, 12);
  text += "M2\n";
  EXPECT_GT(worst_wire_over_motion(text, 50), 3.0);  // 3,000 / 829: it starves as written
  const auto r = limit_feed_to_link(text, serial());
  EXPECT_NEAR(r.wire_feed, 829.4, 1.0);
  EXPECT_DOUBLE_EQ(r.commanded_feed, 3000);
  // 829 mm/min arrives in time: the level below it is 20 % of F3000.
  EXPECT_NE(r.text.find("F600\n"), std::string::npos) << r.text.substr(0, 2000);
  EXPECT_EQ(r.text.find("F900"), std::string::npos);
  // F written only where it changes: a step down at the long move before the
  // stretch (its windows hold one long move and 49 short ones: 1,939 mm/min
  // arrive, F1800), F600 through it, the same steps up after it.
  EXPECT_GE(r.feed_changes, 2u);
  EXPECT_LE(r.feed_changes, 6u);
  EXPECT_NE(r.text.find("F3000\n", r.text.find("F600")), std::string::npos);
  // Only the dense stretch (and the windows reaching into it) runs slower.
  EXPECT_GT(r.length_below, 400 * 0.03 - 1e-9);
  EXPECT_LT(r.share_below(), 0.1);
  EXPECT_LE(worst_wire_over_motion(r.text, 50), 1.0 + 1e-9);
  // Never a feed above the commanded one.
  for (const auto& s : trace_program(r.text).segments) EXPECT_LE(s.feed, 3000);
}

TEST(LinkFeedLimit, ProgramThatStreamsIsLeftAlone) {
  std::string text = "G1F3000\n";
  double x = 0;
  append_moves(text, x, 300, 1.0, 14);
  const auto r = limit_feed_to_link(text, serial());
  EXPECT_EQ(r.text, text);
  EXPECT_EQ(r.length_below, 0);
  EXPECT_EQ(r.feed_changes, 0u);
}

TEST(LinkFeedLimit, UnboundedLinkChangesNothing) {
  std::string text = "G1F3000\n";
  double x = 0;
  append_moves(text, x, 300, 0.01, 25);
  LinkFeedOptions usb;  // bytes_per_second = 0
  EXPECT_EQ(limit_feed_to_link(text, usb).text, text);
}

TEST(LinkFeedLimit, ResultNeverStarvesOnMixedDensities) {
  std::string text = "G1F2500\n";
  double x = 0;
  for (int block = 0; block < 20; ++block) append_moves(text, x, 37 + block * 3, block % 3 == 0 ? 0.02 : 0.4, 15 + block % 7);
  const auto r = limit_feed_to_link(text, serial());
  EXPECT_GT(worst_wire_over_motion(text, 50), 1.0);
  EXPECT_LE(worst_wire_over_motion(r.text, 50), 1.0 + 1e-9);
}

}  // namespace
