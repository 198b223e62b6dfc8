// End-to-end through a real pty: the cncsim program, a host that opens the
// slave side and streams with (or without) GRBL character counting.
#include <gtest/gtest.h>

#include <sys/ioctl.h>

#include <cmath>
#include <deque>
#include <filesystem>

#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/cam/height_field_mesh.hpp"
#include "cncstream/geometry/stl.hpp"
#include "cncstream/gcode/line_lexer.hpp"
#include "pty_process.hpp"

using simtest::Port;
using simtest::SimProcess;

namespace {

bool is_answer(const std::string& l) { return l == "ok" || l.rfind("error:", 0) == 0; }

std::vector<std::string> zigzag_program(int n) {
  std::vector<std::string> lines{"G21 G90 (zig-zag)", "G1 F3000"};
  for (int i = 0; i < n; ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f ; step %d", (i % 2) * 1.5, i * 0.01, i);
    lines.push_back(buf);
  }
  return lines;
}

struct StreamResult {
  std::size_t oks = 0;
  std::vector<std::string> errors;
  std::size_t max_in_flight = 0;
};

// GRBL character counting: cleaned length + 1 per line, at most 127 bytes
// unanswered; every ok/error answers the oldest line.
StreamResult stream_counting(Port& port, const std::vector<std::string>& lines) {
  StreamResult r;
  std::deque<std::size_t> in_flight;
  std::size_t used = 0, next = 0;
  while (next < lines.size() || !in_flight.empty()) {
    while (next < lines.size()) {
      const auto clean = cncstream::gcode::clean_line(lines[next]);
      const std::size_t cost = clean.text.size() + 1;
      if (used + cost > 127) break;
      port.write_all(clean.text + "\n");
      in_flight.push_back(cost);
      used += cost;
      r.max_in_flight = std::max(r.max_in_flight, used);
      ++next;
    }
    const std::string l = port.read_line(10);
    if (l == "<TIMEOUT>" || l == "<EOF>") {
      r.errors.push_back(l);
      return r;
    }
    if (!is_answer(l)) continue;
    used -= in_flight.front();
    in_flight.pop_front();
    if (l == "ok") ++r.oks;
    else r.errors.push_back(l);
  }
  return r;
}

std::string wait_idle_status(Port& port) {
  for (int i = 0; i < 500; ++i) {
    port.write_all("?");
    const std::string s = port.read_until([](const std::string& l) { return l.rfind("<", 0) == 0; });
    if (s.rfind("<Idle", 0) == 0) return s;
    usleep(2000);
  }
  return "never idle";
}

std::size_t dropped_from_stderr(const std::string& err) {
  const auto end = err.find(" RX bytes dropped");
  if (end == std::string::npos) return 0;
  const auto start = err.rfind(' ', end - 1);
  return std::stoul(err.substr(start + 1, end - start - 1));
}

}  // namespace

TEST(Pty, CountingSenderStreamsThousandsOfLinesWithoutOverflow) {
  const std::string link = "/tmp/cncsim_test_link_" + std::to_string(getpid());
  SimProcess sim({"--speed", "max", "--strict", "--link", link});
  EXPECT_EQ(std::filesystem::read_symlink(link).string(), sim.slave());
  Port port(link);
  EXPECT_EQ(port.read_until([](const std::string& l) { return !l.empty(); }), "Grbl 1.1h ['$' for help]");
  const auto program = zigzag_program(3000);
  const StreamResult r = stream_counting(port, program);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  EXPECT_EQ(r.oks, program.size());
  EXPECT_GT(r.max_in_flight, 100u);  // the buffer was really used
  EXPECT_EQ(wait_idle_status(port).substr(0, 33), "<Idle|MPos:1.500,29.990,0.000|FS:");
  EXPECT_EQ(sim.stop(), 0);
  EXPECT_EQ(dropped_from_stderr(sim.stderr_text()), 0u);
  EXPECT_FALSE(std::filesystem::exists(link));  // the link goes with the simulator
}

TEST(Pty, CarelessSenderOverflowsAndStrictCatchesIt) {
  const auto program = zigzag_program(400);
  std::string all;
  for (const auto& l : program) all += l + "\n";
  // At --speed max the firmware never waits, so nothing can overflow: a
  // careless host overflows a machine that takes time to move (here 5x).
  {
    SimProcess sim({"--speed", "5", "--strict"});
    Port port(sim.slave());
    try {
      port.write_all(all);
    } catch (const std::exception&) {
      // the simulator may already have closed the pty
    }
    EXPECT_EQ(sim.wait(), 2);
    EXPECT_NE(sim.stderr_text().find("RX buffer overflow"), std::string::npos) << sim.stderr_text();
  }
  {
    SimProcess sim({"--speed", "5"});
    Port port(sim.slave());
    port.write_all(all);
    port.read_until([](const std::string&) { return false; }, 0.5);
    EXPECT_EQ(sim.stop(), 0);
    EXPECT_GT(dropped_from_stderr(sim.stderr_text()), 0u) << sim.stderr_text();
  }
}

TEST(Pty, RealtimeBytesAndAlarms) {
  SimProcess sim({"--speed", "1"});
  Port port(sim.slave());
  port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
  port.write_all("G1 X20 F600\n");
  EXPECT_EQ(port.read_line(), "ok");
  usleep(300000);
  port.write_all("?");
  EXPECT_EQ(port.read_line().substr(0, 4), "<Run");
  port.write_all("!");
  usleep(1500000);  // 10 mm/s, a = 10: stops within 1 s
  port.write_all("?");
  EXPECT_EQ(port.read_line().substr(0, 7), "<Hold:0");
  port.write_all("~");
  usleep(100000);
  port.write_all("?");
  EXPECT_EQ(port.read_line().substr(0, 4), "<Run");
  port.write_all("\x18");
  EXPECT_EQ(port.read_line(), "ALARM:3");
  port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
  EXPECT_EQ(port.read_line(), "[MSG:'$H'|'$X' to unlock]");
  port.write_all("G0 X0\n");
  EXPECT_EQ(port.read_line(), "error:9");
  EXPECT_EQ(sim.stop(), 0);
}

TEST(Pty, FaultFlags) {
  {
    SimProcess sim({"--speed", "max", "--error-at", "2:33", "--alarm-at", "3:2"});
    Port port(sim.slave());
    port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
    port.write_all("G0 X1\n");
    EXPECT_EQ(port.read_line(), "ok");
    port.write_all("G0 X2\n");
    EXPECT_EQ(port.read_line(), "error:33");
    port.write_all("G0 X3\n");
    EXPECT_EQ(port.read_line(), "ALARM:2");
    EXPECT_EQ(port.read_line(), "[MSG:Reset to continue]");
    sim.stop();
  }
  {
    SimProcess sim({"--speed", "max", "--vanish-after", "2", "--stall-at", "1:0.3"});
    Port port(sim.slave());
    port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
    port.write_all("G0 X1\n");
    EXPECT_EQ(port.read_line(0.1), "<TIMEOUT>");  // stalled
    EXPECT_EQ(port.read_line(2.0), "ok");
    port.write_all("G0 X2\nG0 X3\n");
    EXPECT_EQ(port.read_line(), "ok");
    EXPECT_EQ(port.read_line(), "<EOF>");  // the port went away
    EXPECT_EQ(sim.wait(), 0);
    EXPECT_NE(sim.stderr_text().find("vanished after 2"), std::string::npos);
  }
  {
    SimProcess sim({"--speed", "max", "--drop-every", "2"});
    Port port(sim.slave());
    port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
    port.write_all("G0X1\n");  // arrives as "GX"
    EXPECT_EQ(port.read_line(), "error:2");
    sim.stop();
  }
}

TEST(Pty, MaterialRemovalKnownAnswer) {
  const std::string result = "/tmp/cncsim_test_result_" + std::to_string(getpid()) + ".f32";
  SimProcess sim({"--speed", "max", "--stock", "0,0,-10:20,20,0", "--resolution", "0.1", "--tool", "flat:6",
                  "--result", result});
  Port port(sim.slave());
  port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
  const StreamResult r = stream_counting(
      port, {"G0 Z5", "G0 X5 Y10", "G1 Z-2 F300", "G1 X15", "G0 Z5", "G0 X10 Y5", "G1 Z-1", "G1 Y15", "G0 Z5"});
  EXPECT_TRUE(r.errors.empty());
  wait_idle_status(port);
  EXPECT_EQ(sim.stop(), 0);
  const auto field = cncstream::cam::read_height_field(result);
  auto z_at = [&](double x, double y) {
    const auto i = static_cast<std::size_t>(std::lround((x - field.grid.x0) / field.grid.dx));
    const auto j = static_cast<std::size_t>(std::lround((y - field.grid.y0) / field.grid.dy));
    return field.z[j * field.grid.nx + i];
  };
  EXPECT_NEAR(z_at(10, 10), -2, 1e-6);   // slot along X at Z-2
  EXPECT_NEAR(z_at(5, 12.9), -2, 1e-6);  // within the 3 mm radius
  EXPECT_NEAR(z_at(5, 13.2), 0, 1e-6);   // just outside the slot
  EXPECT_NEAR(z_at(10, 14), -1, 1e-6);   // the crossing slot along Y at Z-1
  EXPECT_NEAR(z_at(2.5, 10), -2, 1e-6);  // the plunge at X5 reaches X2
  EXPECT_NEAR(z_at(1.5, 10), 0, 1e-6);   // beyond the slot's start (5 - 3 = 2)
  EXPECT_NEAR(z_at(18.5, 10), 0, 1e-6);
  std::filesystem::remove(result);
  std::filesystem::remove(result + ".txt");
}

TEST(Pty, DesignVerifiedAtExitWithAToolTable) {
  const std::string base = "/tmp/cncsim_test_design_" + std::to_string(getpid());
  // The design: a 20 x 20 mm block with its top at Z0; the stock is its box.
  const auto grid = cncstream::cam::GridSpec::covering(0, 0, 20, 20, 1, 1);
  cncstream::cam::write_height_field_stl(base + ".stl", grid, std::vector<double>(grid.size(), 0.0), -10);
  SimProcess sim({"--speed", "max", "--design", base + ".stl", "--resolution", "0.1", "--tool-table",
                  "1=flat:6,2=ball:2", "--result", base + "-cut.f32", "--png", base + "-map.png"});
  Port port(sim.slave());
  port.read_until([](const std::string& l) { return l.rfind("Grbl", 0) == 0; });
  // T1 cuts a 2 mm slot into the design (a gouge), T2 a 0.5 mm ball groove.
  const StreamResult r = stream_counting(port, {"T1", "G0 Z5", "G0 X5 Y5", "G1 Z-2 F300", "G1 X15", "G0 Z5", "T2",
                                                "G0 X5 Y15", "G1 Z-0.5", "G1 X15", "G0 Z5"});
  EXPECT_TRUE(r.errors.empty());
  wait_idle_status(port);
  EXPECT_EQ(sim.stop(), 3) << sim.stderr_text();  // 3: the verify found a gouge
  const std::string err = sim.stderr_text();
  EXPECT_NE(err.find("largest gouge 2.0000 mm"), std::string::npos) << err;
  EXPECT_TRUE(std::filesystem::exists(base + "-map.png"));
  const auto field = cncstream::cam::read_height_field(base + "-cut.f32");
  auto z_at = [&](double x, double y) {
    const auto i = static_cast<std::size_t>(std::lround((x - field.grid.x0) / field.grid.dx));
    const auto j = static_cast<std::size_t>(std::lround((y - field.grid.y0) / field.grid.dy));
    return field.z[j * field.grid.nx + i];
  };
  EXPECT_NEAR(z_at(10, 7.5), -2, 1e-6);                          // flat:6 slot, 3 mm radius
  EXPECT_NEAR(z_at(10, 15.5), -0.5 + 1 - std::sqrt(0.75), 1e-6);  // ball:2 groove, 0.5 mm aside
  const auto solid = cncstream::geometry::summarize(cncstream::geometry::load_stl(base + "-cut.stl").mesh);
  EXPECT_TRUE(solid.closed()) << solid.to_string();
  for (const char* ext : {".stl", "-cut.f32", "-cut.f32.txt", "-cut.stl", "-map.png"}) std::filesystem::remove(base + ext);
}

// kill -9 of a host that holds the port exclusively (TIOCEXCL, as cncstream's
// transport does) must not lock the next host out: a real serial port forgets
// exclusive mode at its last close, and the simulator keeps its pty open.
TEST(Pty, AHostKilledHoldingThePortExclusivelyDoesNotLockOutTheNext) {
  SimProcess sim({"--speed", "max"});
  const pid_t host = fork();
  if (host == 0) {
    const int fd = open(sim.slave().c_str(), O_RDWR | O_NOCTTY);
    if (fd < 0 || ioctl(fd, TIOCEXCL) != 0) _exit(1);
    raise(SIGKILL);
  }
  int st = 0;
  waitpid(host, &st, 0);
  ASSERT_TRUE(WIFSIGNALED(st)) << "the host could not take the port";
  // A user without CAP_SYS_ADMIN gets EBUSY while the flag stands; root
  // opens anyway, so read the flag itself (TIOCGEXCL).
  int excl = 1;
  for (int i = 0; i < 500 && excl != 0; ++i) {
    const int fd = open(sim.slave().c_str(), O_RDWR | O_NOCTTY);
    if (fd >= 0) {
      if (ioctl(fd, TIOCGEXCL, &excl) != 0) excl = -1;
      close(fd);
    }
    if (excl != 0) usleep(10000);  // the simulator has not seen the close yet
  }
  EXPECT_EQ(excl, 0) << "the pty is still exclusive to a host that no longer exists";
}
