// The simulator's grblHAL personality and its manual tool change ($341, the
// Tool state at M6, 0xA3, cycle start), as grblHAL core's tool_change.c,
// state_machine.c and gcode.c behave; GRBL 1.1 unchanged (M6 is error:20).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cncsim/machine.hpp"
#include "support/routine_bench.hpp"

using cncstream::test::controller_lines;

namespace {

cncsim::MachineOptions grblhal_options() {
  cncsim::MachineOptions o;
  o.firmware = cncsim::Firmware::GrblHal;
  o.instant_waits = true;
  return o;
}

struct Bench {
  cncsim::Machine m;
  explicit Bench(cncsim::MachineOptions o) : m(std::move(o)) { m.take_output(); }
  // Sends bytes, runs until nothing more happens by itself, returns the lines printed.
  std::vector<std::string> send(const std::string& bytes) {
    m.receive(bytes);
    m.run_until_idle(60);
    return controller_lines(m.take_output());
  }
  std::string state() { return m.state_name(); }
};

int count(const std::vector<std::string>& v, const std::string& s) {
  int n = 0;
  for (const auto& l : v) n += l == s;
  return n;
}

bool has_prefix(const std::vector<std::string>& v, const std::string& p) {
  for (const auto& l : v)
    if (l.rfind(p, 0) == 0) return true;
  return false;
}

}  // namespace

TEST(GrblHalToolChange, Grbl11IsUnchangedM6IsError20AndThereIsNo341) {
  cncsim::MachineOptions o;
  o.instant_waits = true;
  Bench b(o);
  EXPECT_EQ(b.send("T2 M6\n"), std::vector<std::string>{"error:20"});
  EXPECT_EQ(b.send("$341=0\n"), std::vector<std::string>{"error:3"});
  EXPECT_EQ(b.send("\xA3"), std::vector<std::string>{});  // an extended byte it does not know: thrown away
  EXPECT_EQ(b.state(), "Idle");
}

TEST(GrblHalToolChange, IdentifiesAsGrblHalWith341AndItsRxBuffer) {
  cncsim::Machine m(grblhal_options());
  EXPECT_NE(m.take_output().find("GrblHAL 1.1f ['$' or '$HELP' for help]"), std::string::npos);
  m.receive("$I\n$$\n$341=5\n$341=4\n");
  m.run_until_idle(10);
  const auto out = controller_lines(m.take_output());
  EXPECT_TRUE(has_prefix(out, "[FIRMWARE:grblHAL]"));
  EXPECT_TRUE(has_prefix(out, "[OPT:VNM,15,1024,3]"));
  EXPECT_TRUE(has_prefix(out, "$341=0"));
  EXPECT_EQ(count(out, "error:3"), 1) << "$341 is 0-4";
  EXPECT_EQ(m.settings().get(341), 4);
  EXPECT_EQ(m.rx_capacity(), 1024u);
}

TEST(GrblHalToolChange, M6EntersToolJogAndZeroWorkThereMotionAndProbeAreError40CycleStartGoesOn) {
  Bench b(grblhal_options());
  // The program's lines after the M6 arrive with it: the firmware stops reading at the M6.
  auto out = b.send("G0 X5\nT2 M6\nG0 X10\n");
  EXPECT_EQ(count(out, "ok"), 2) << "G0 X5 and the M6; G0 X10 is not read";
  EXPECT_EQ(b.state(), "Tool");
  EXPECT_NE(b.m.status_report().find("<Tool|"), std::string::npos);
  EXPECT_NEAR(b.m.machine_position().x, 5, 1e-9);
  // Nothing is read until the acknowledge: a line waits.
  EXPECT_TRUE(b.send("G0 Y3\n").empty());
  EXPECT_EQ(b.state(), "Tool");
  // 0xA3: the waiting lines (G0 X10, G0 Y3) are kept aside; new ones are read.
  EXPECT_TRUE(b.send("\xA3").empty());
  out = b.send("$J=G91 Z-4 F600\n");
  EXPECT_EQ(out, std::vector<std::string>{"ok"});
  EXPECT_EQ(b.state(), "Tool") << "back in Tool after the jog";
  EXPECT_NEAR(b.m.machine_position().z, -4, 1e-9);
  EXPECT_EQ(b.send("G0 X20\n"), std::vector<std::string>{"error:40"});
  EXPECT_EQ(b.send("G38.2 Z-10 F100\n"), std::vector<std::string>{"error:40"});
  EXPECT_EQ(b.send("G1 X1 F100\n"), std::vector<std::string>{"error:40"});
  EXPECT_EQ(b.send("G10 L20 P0 Z0\n"), std::vector<std::string>{"ok"});
  EXPECT_NEAR(b.m.work_position().z, 0, 1e-9);
  EXPECT_NEAR(b.m.machine_position().x, 5, 1e-9) << "nothing moved but the jog";
  // Cycle start: the change ends; the kept lines run (G0 X10, G0 Y3).
  out = b.send("~");
  EXPECT_EQ(count(out, "ok"), 2);
  EXPECT_EQ(b.state(), "Idle");
  EXPECT_NEAR(b.m.machine_position().x, 10, 1e-9);
  EXPECT_NEAR(b.m.machine_position().y, 3, 1e-9);
  EXPECT_NEAR(b.m.machine_position().z, -4, 1e-9);
  EXPECT_EQ(b.send("G0 X20\n"), std::vector<std::string>{"ok"}) << "motion is allowed again";
  // The same tool again: nothing to change.
  EXPECT_EQ(b.send("M6 T2\n"), std::vector<std::string>{"ok"});
  EXPECT_EQ(b.state(), "Idle");
}

TEST(GrblHalToolChange, Mode4IgnoresM6AndModes1To3NeedHoming) {
  Bench b(grblhal_options());
  ASSERT_EQ(b.send("$341=4\n"), std::vector<std::string>{"ok"});
  EXPECT_EQ(b.send("T2 M6\nG0 X3\n"), (std::vector<std::string>{"ok", "ok"}));
  EXPECT_EQ(b.state(), "Idle");
  EXPECT_NEAR(b.m.machine_position().x, 3, 1e-9);
  ASSERT_EQ(b.send("$341=1\n"), std::vector<std::string>{"ok"});
  EXPECT_EQ(b.send("T3 M6\n"), std::vector<std::string>{"error:46"});
  EXPECT_EQ(b.state(), "Idle");
}

TEST(GrblHalToolChange, ResetInTheToolStateDropsTheKeptLines) {
  Bench b(grblhal_options());
  b.send("T2 M6\nG0 X10\n\xA3");
  ASSERT_EQ(b.state(), "Tool");
  const auto out = b.send("\x18");
  EXPECT_TRUE(has_prefix(out, "GrblHAL 1.1f"));
  EXPECT_EQ(b.state(), "Idle");
  EXPECT_EQ(b.send("~"), std::vector<std::string>{});
  EXPECT_NEAR(b.m.machine_position().x, 0, 1e-9) << "the line kept aside never ran";
  EXPECT_EQ(b.send("G0 X1\n"), std::vector<std::string>{"ok"});
}
