// The replay file: reports, plug events, comments, and errors that name the
// file, the line and the bad token.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "cncstream/pendant/replay_source.hpp"

using namespace cncstream::pendant;

namespace {

std::string parse_error(const std::string& text) {
  std::istringstream in(text);
  try {
    parse_replay(in, "wheel.txt");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

}  // namespace

TEST(ReplaySource, ReportsCommentsAndPlugEvents) {
  std::istringstream in(
      "# a recorded session\n"
      "\n"
      "0 04 ba 00 00 0f 11 00 ba   # knob 0.1, axis X\n"
      "300 04 00 00 00 0f 11 03 00\n"
      "  300\t4 0 0 0 F 11 FD 0  \n"
      "450.5 unplug\n"
      "900 plug # back\n");
  const auto e = parse_replay(in, "wheel.txt");
  ASSERT_EQ(e.size(), 5u);
  EXPECT_EQ(e[0].at_ms, 0);
  EXPECT_EQ(e[0].line, 3);
  EXPECT_EQ(e[0].kind, ReplayKind::Report);
  EXPECT_EQ(e[0].report, (InputReport{0x04, 0xba, 0x00, 0x00, 0x0f, 0x11, 0x00, 0xba}));
  EXPECT_EQ(e[1].at_ms, 300);
  EXPECT_EQ(e[1].report, (InputReport{0x04, 0x00, 0x00, 0x00, 0x0f, 0x11, 0x03, 0x00}));
  EXPECT_EQ(e[2].line, 5);
  EXPECT_EQ(e[2].report, (InputReport{0x04, 0x00, 0x00, 0x00, 0x0f, 0x11, 0xfd, 0x00}));
  EXPECT_EQ(e[3].kind, ReplayKind::Unplug);
  EXPECT_DOUBLE_EQ(e[3].at_ms, 450.5);
  EXPECT_EQ(e[4].kind, ReplayKind::Plug);
  EXPECT_EQ(e[4].line, 7);
}

TEST(ReplaySource, ErrorsNameFileLineAndToken) {
  EXPECT_EQ(parse_error("0 04 00 00 00 0f 11 00 00\n# c\n10 04 00 zz 00 0f 11 00 00\n"),
            "wheel.txt:3: byte 2 'zz' is not a hex byte (00-ff)");
  EXPECT_EQ(parse_error("10 04 00 00 00 0f 11 100 00\n"), "wheel.txt:1: byte 6 '100' is not a hex byte (00-ff)");
  EXPECT_EQ(parse_error("abc 04 00 00 00 0f 11 00 00\n"),
            "wheel.txt:1: 'abc' is not a time in milliseconds (a number >= 0 starts each line)");
  EXPECT_EQ(parse_error("-5 04 00 00 00 0f 11 00 00\n"),
            "wheel.txt:1: '-5' is not a time in milliseconds (a number >= 0 starts each line)");
  EXPECT_EQ(parse_error("100 04 00 00 00 0f 11 00 00\n50 04 00 00 00 0f 11 00 00\n"),
            "wheel.txt:2: time 50 ms is earlier than the line before (times must not decrease)");
  EXPECT_EQ(parse_error("100 04 00 00 00 0f 11 00\n"),
            "wheel.txt:1: expected the time and 8 report bytes in hex (or 'unplug' / 'plug'), got 7 tokens after the time");
  EXPECT_EQ(parse_error("100\n"),
            "wheel.txt:1: expected the time and 8 report bytes in hex (or 'unplug' / 'plug'), got 0 tokens after the time");
  EXPECT_EQ(parse_error("100 unplugged\n"),
            "wheel.txt:1: expected the time and 8 report bytes in hex (or 'unplug' / 'plug'), got 1 token after the time");
  // Hex that no pendant sends: the decoder's reason.
  EXPECT_EQ(parse_error("100 04 00 00 00 0f 31 00 00\n"),
            "wheel.txt:1: byte 5 (axis knob) is 0x31: expected 0x06 (off) or 0x11-0x16 (X-C)");
}

TEST(ReplaySource, MissingFileIsNamed) {
  const auto path = std::filesystem::temp_directory_path() / "cncstream_no_such_replay.txt";
  std::filesystem::remove(path);
  try {
    load_replay(path);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}
