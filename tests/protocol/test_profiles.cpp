#include <gtest/gtest.h>

#include <fstream>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/identifier.hpp"
#include "cncstream/protocol/link_model.hpp"

using namespace cncstream::protocol;

namespace {
const std::vector<FirmwareProfile>& profiles() {
  static const auto p = load_firmware_profiles(CNCSTREAM_SOURCE_DIR "/firmware-profiles");
  return p;
}
const FirmwareProfile& by_id(const std::string& id) {
  for (const auto& p : profiles())
    if (p.id == id) return p;
  throw std::runtime_error("no profile " + id);
}
}  // namespace

TEST(Profiles, Grbl11HasFullTables) {
  const auto& g = by_id("grbl-1.1");
  EXPECT_EQ(g.rx_buffer_size, 128u);
  EXPECT_EQ(g.line_length_limit, 80u);
  for (int c : {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17}) EXPECT_TRUE(g.errors.count(c)) << c;
  for (int c = 20; c <= 38; ++c) EXPECT_TRUE(g.errors.count(c)) << c;
  for (int c = 1; c <= 9; ++c) EXPECT_TRUE(g.alarms.count(c)) << c;
  EXPECT_EQ(g.error_info(22).name, "Undefined feed rate");
  EXPECT_TRUE(g.alarm_info(2).reset_required);
  EXPECT_TRUE(g.alarm_info(1).position_lost);
  EXPECT_EQ(*g.realtime_byte(Realtime::FeedOvPlus10), 0x91);
  EXPECT_EQ(*g.realtime_byte(Realtime::JogCancel), 0x85);
  EXPECT_FALSE(g.realtime_byte(Realtime::ToolChangeAck));
  EXPECT_EQ(g.error_info(99).name, "Unknown error");
}

TEST(Profiles, InheritanceMergesTables) {
  const auto& h = by_id("grblhal");
  EXPECT_EQ(h.rx_buffer_size, 1024u);
  EXPECT_TRUE(h.errors.count(22));  // inherited
  EXPECT_TRUE(h.errors.count(84));  // own
  EXPECT_TRUE(h.alarms.count(18));
  EXPECT_EQ(*h.realtime_byte(Realtime::ToolChangeAck), 0xA3);
  EXPECT_EQ(*h.realtime_byte(Realtime::FeedHold), '!');
  const auto& f = by_id("fluidnc");
  EXPECT_EQ(f.line_length_limit, 255u);
  EXPECT_TRUE(f.errors.count(152));
  EXPECT_FALSE(f.realtime_byte(Realtime::FullStatusReport));  // 0x87 is a macro on FluidNC
  const auto& m = by_id("marlin");
  EXPECT_EQ(m.flow, FlowControl::SendResponse);
  EXPECT_FALSE(m.realtime_byte(Realtime::FeedHold));
}

TEST(Profiles, ErrorsNameFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path() / "cncstream_profile_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "bad.toml") << "family = \"grbl\"\nbanner_patterns = ['x']\nrx_buffer_size = \"big\"\n";
  }
  try {
    load_firmware_profile(dir / "bad.toml");
    FAIL();
  } catch (const ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:3"), std::string::npos) << e.what();
  }
  { std::ofstream(dir / "bad2.toml") << "family = \"grbl\"\nbanner_patterns = ['(']\n"; }
  EXPECT_THROW(load_firmware_profile(dir / "bad2.toml"), ProfileError);
  { std::ofstream(dir / "bad3.toml") << "family = \"grbl\"\nbanner_patterns = ['x']\n[realtime]\nwarp = 3\n"; }
  EXPECT_THROW(load_firmware_profile(dir / "bad3.toml"), ProfileError);
  {
    std::ofstream(dir / "bad4.toml") << "family = \"marlin\"\nbanner_patterns = ['x']\n[[messages]]\n"
                                        "pattern = 'halted'\ntext = 'no advice given'\n";
  }
  try {
    load_firmware_profile(dir / "bad4.toml");
    FAIL();
  } catch (const ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("'pattern', 'text' and 'action'"), std::string::npos) << e.what();
  }
  // Found by tests/fuzz: a table header that does not start with a key made
  // toml++ 3.3 assert (undefined behaviour in a release build).
  for (const char* header : {"[[^larms]]", "[ =x]", "[[ .a]]"}) {
    { std::ofstream(dir / "bad5.toml") << "family = \"grbl\"\nbanner_patterns = ['x']\n" << header << "\ncode = 1\n"; }
    try {
      load_firmware_profile(dir / "bad5.toml");
      FAIL() << header;
    } catch (const ProfileError& e) {
      EXPECT_NE(std::string(e.what()).find("bad5.toml:3"), std::string::npos) << e.what();
    }
  }
  // The rest of what toml++ 3.3 misbehaves on (the daemon's configuration
  // found them): a character beyond ASCII in a bare value, an array element
  // starting with '}', a date followed by a lone digit.
  for (const char* line : {"name = \xC3\xA9", "a = [}]", "d = 2051-06-01 0 "}) {
    { std::ofstream(dir / "bad6.toml") << "family = \"grbl\"\nbanner_patterns = ['x']\n" << line << "\n"; }
    try {
      load_firmware_profile(dir / "bad6.toml");
      FAIL() << line;
    } catch (const ProfileError& e) {
      EXPECT_NE(std::string(e.what()).find("bad6.toml:3"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Profiles, MarlinExplainsItsTextErrors) {
  const auto m = load_firmware_profile(CNCSTREAM_SOURCE_DIR "/firmware-profiles/marlin.toml");
  ASSERT_TRUE(m.message_info("Printer halted. kill() called!"));
  EXPECT_TRUE(m.message_info("Printer halted. kill() called!")->position_lost);
  EXPECT_EQ(m.message_info("Homing Failed")->name, "Homing failed");
  EXPECT_FALSE(m.message_info("something new"));
}

namespace {
Identification identify(const std::vector<std::string>& before, const std::vector<std::string>& answer,
                        std::string* sent = nullptr) {
  FirmwareIdentifier id(profiles());
  id.start(0);
  for (const auto& l : before) id.on_line(l, 0.1);
  const auto q = id.take_output();
  if (sent) *sent = q;
  for (const auto& l : answer) id.on_line(l, 0.2);
  id.tick(10);  // timeouts if the answer did not finish it (banner, status, query)
  id.tick(20);
  id.tick(30);
  return id.result();
}
}  // namespace

TEST(Identify, Grbl11ByBannerAndOpt) {
  std::string q;
  auto r = identify({"Grbl 1.1h ['$' for help]"}, {"[VER:1.1h.20190830:]", "[OPT:V,15,128]", "ok"}, &q);
  EXPECT_EQ(q, "$I\n");
  EXPECT_EQ(r.profile.id, "grbl-1.1");
  EXPECT_TRUE(r.recognised);
  EXPECT_EQ(r.profile.rx_buffer_size, 128u);
}

TEST(Identify, GrblHalRefinedByFirmwareLineAndRxFromOpt) {
  auto r = identify({"Grbl 1.1f ['$' for help]"},
                    {"[VER:1.1f.20230129:]", "[OPT:VNMSL,35,1024,3,0]", "[FIRMWARE:grblHAL]", "ok"});
  EXPECT_EQ(r.profile.id, "grblhal");
  EXPECT_EQ(r.profile.planner_blocks, 35);
  r = identify({"GrblHAL 1.1f ['$' or '$HELP' for help]"}, {"[VER:1.1f.20230129:]", "[OPT:VNMSL,35,4096,3]", "ok"});
  EXPECT_EQ(r.profile.id, "grblhal");
  EXPECT_EQ(r.profile.rx_buffer_size, 4096u);
}

TEST(Identify, FluidNc) {
  auto r = identify({"Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]"}, {"[VER:3.7 FluidNC v3.7.8:]", "[OPT:PHS]", "ok"});
  EXPECT_EQ(r.profile.id, "fluidnc");
}

TEST(Identify, MarlinUsesM115) {
  FirmwareIdentifier id(profiles());
  id.start(0);
  id.on_line("start", 0.1);
  id.on_line("echo:Marlin 2.1.2.1", 0.1);
  EXPECT_EQ(id.take_output(), "M115\n");
  id.on_line("FIRMWARE_NAME:Marlin 2.1.2.1 (Jun 1 2023) SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin", 0.2);
  id.on_line("Cap:SERIAL_XON_XOFF:0", 0.2);
  id.on_line("ok", 0.3);
  EXPECT_EQ(id.take_output(), "");  // exactly one query: the answer is not mistaken for a new banner
  ASSERT_TRUE(id.done());
  EXPECT_EQ(id.result().profile.id, "marlin");
  EXPECT_EQ(id.result().query_lines.size(), 2u);
}

TEST(Identify, UnknownFallsBackToConservativeSubsetWithWarning) {
  auto r = identify({"SuperCNC 2.0 ready"}, {});
  EXPECT_FALSE(r.recognised);
  EXPECT_FALSE(r.profile.extended_realtime);
  EXPECT_EQ(r.profile.rx_buffer_size, 128u);
  EXPECT_FALSE(r.profile.realtime_byte(Realtime::FeedOvPlus10));  // no extended byte
  EXPECT_EQ(*r.profile.realtime_byte(Realtime::FeedHold), '!');
  EXPECT_FALSE(r.warnings.empty());
}

TEST(Identify, NoBannerAsksWithDollarIOnceTheControllerIsIdle) {
  FirmwareIdentifier id(profiles());
  id.start(0);
  id.tick(1.0);
  EXPECT_EQ(id.take_output(), "");
  id.tick(3.5);
  EXPECT_EQ(id.take_output(), "?") << "no banner: is it busy?";
  id.on_line("<Idle|MPos:0.000,0.000,0.000|FS:0,0>", 3.55);
  id.tick(3.7);
  EXPECT_EQ(id.take_output(), "?");
  id.on_line("<Idle|MPos:0.000,0.000,0.000|FS:0,0>", 3.75);
  EXPECT_EQ(id.take_output(), "$I\n");
  id.on_line("<Idle|MPos:0.000,0.000,0.000|FS:0,0>", 3.76);  // a late answer to a '?'
  id.on_line("[VER:1.1h.20190830:]", 3.8);
  id.on_line("ok", 3.9);
  ASSERT_TRUE(id.done());
  EXPECT_EQ(id.result().profile.id, "grbl-1.1");
  EXPECT_EQ(id.result().query_lines, std::vector<std::string>{"[VER:1.1h.20190830:]"});
  EXPECT_FALSE(id.result().warnings.empty());
}

// A board that did not reset when the port opened may still be running the
// lines of a host that died: their answers are not answers to $I (taken for
// them, the next job's character count went wrong and the controller's
// buffer overflowed: found by the crash runs at real speed).
TEST(Identify, ABusyControllerIsLeftToFinishAndItsAnswersAreIgnored) {
  FirmwareIdentifier id(profiles());
  id.start(0);
  id.tick(3.5);
  EXPECT_EQ(id.take_output(), "?");
  id.on_line("<Run|MPos:10.000,0.000,0.000|FS:500,0>", 3.55);
  const auto notes = id.take_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("busy (Run)"), std::string::npos) << notes[0];
  double t = 3.55;
  for (int i = 0; i < 20; ++i) {  // four seconds of an earlier host's lines
    t += 0.2;
    id.tick(t);
    EXPECT_EQ(id.take_output(), "?");
    id.on_line("ok", t + 0.01);
    id.on_line(i == 10 ? "<Idle|MPos:20.000,0.000,0.000|FS:0,0>" : "<Run|MPos:20.000,0.000,0.000|FS:500,0>", t + 0.02);
  }
  EXPECT_FALSE(id.done());
  EXPECT_TRUE(id.take_notes().empty()) << "said once";
  id.tick(t + 0.2);
  id.on_line("<Idle|MPos:30.000,0.000,0.000|FS:0,0>", t + 0.21);
  id.on_line("ok", t + 0.25);  // the last of them: the calm starts again
  id.tick(t + 0.4);
  id.on_line("<Idle|MPos:30.000,0.000,0.000|FS:0,0>", t + 0.41);
  id.tick(t + 0.6);
  EXPECT_EQ(id.take_output(), "???");
  id.on_line("<Idle|MPos:30.000,0.000,0.000|FS:0,0>", t + 0.61);
  EXPECT_EQ(id.take_output(), "$I\n");
  id.on_line("ok", t + 0.62);  // one more stale answer: no version lines before it
  EXPECT_FALSE(id.done());
  id.on_line("[VER:1.1h.20190830:]", t + 0.7);
  id.on_line("[OPT:V,15,128]", t + 0.7);
  id.on_line("ok", t + 0.8);
  ASSERT_TRUE(id.done());
  EXPECT_EQ(id.result().profile.id, "grbl-1.1");
}

TEST(Identify, AControllerThatAnswersNoStatusIsAskedAfterTheQueryTimeout) {
  FirmwareIdentifier id(profiles());
  id.start(0);
  id.tick(3.5);
  EXPECT_EQ(id.take_output(), "?");
  id.tick(3.7);
  EXPECT_EQ(id.take_output(), "?");
  id.tick(5.6);  // the query timeout after the first '?'
  EXPECT_EQ(id.take_output(), "$I\n");
}

// The link each profile describes (protocol/link_model.hpp).
TEST(LinkModel, ProfilesDescribeTheirLinks) {
  using namespace cncstream::protocol;
  const auto dir = std::filesystem::path(CNCSTREAM_SOURCE_DIR) / "firmware-profiles";
  const auto grbl = link_model(load_firmware_profile(dir / "grbl-1.1.toml"));
  EXPECT_DOUBLE_EQ(grbl.bytes_per_second, 11520);
  EXPECT_EQ(grbl.rx_bytes, 128u);
  EXPECT_EQ(grbl.planner_blocks, 15u);
  const auto hal = link_model(load_firmware_profile(dir / "grblhal.toml"));
  EXPECT_DOUBLE_EQ(hal.bytes_per_second, 0);  // native USB
  EXPECT_EQ(hal.rx_bytes, 1024u);
  EXPECT_EQ(hal.planner_blocks, 35u);
  const auto fluid = link_model(load_firmware_profile(dir / "fluidnc.toml"));
  EXPECT_DOUBLE_EQ(fluid.bytes_per_second, 11520);
  EXPECT_EQ(fluid.rx_bytes, 256u);
  // --link-rate replaces the profile's rate.
  EXPECT_DOUBLE_EQ(link_model(load_firmware_profile(dir / "grbl-1.1.toml"), 23040).bytes_per_second, 23040);
}

TEST(LinkModel, LinkRateText) {
  using cncstream::protocol::parse_link_rate;
  EXPECT_DOUBLE_EQ(parse_link_rate("11520"), 11520);
  EXPECT_DOUBLE_EQ(parse_link_rate("230400baud"), 23040);
  EXPECT_DOUBLE_EQ(parse_link_rate("usb"), 0);
  EXPECT_THROW(parse_link_rate("fast"), std::invalid_argument);
  EXPECT_THROW(parse_link_rate("-5"), std::invalid_argument);
}
