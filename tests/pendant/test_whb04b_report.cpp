// The WHB04B input decoder and tracker against byte fixtures: every key,
// Fn + key, each knob position, the wheel both ways, sleep and wake, and
// bytes no pendant sends.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cncstream/pendant/whb04b_report.hpp"

using namespace cncstream::pendant;

namespace {

PendantReport decoded(const InputReport& b) {
  std::string why;
  const auto r = decode_report(b, &why);
  EXPECT_TRUE(r) << hex_bytes(b.data(), b.size()) << ": " << why;
  return r.value_or(PendantReport{});
}

std::string decode_error(const InputReport& b) {
  std::string why;
  EXPECT_FALSE(decode_report(b, &why)) << hex_bytes(b.data(), b.size()) << " decoded";
  return why;
}

}  // namespace

TEST(Whb04bReport, EveryKeyAlone) {
  struct Case {
    InputReport bytes;
    Key key;
  };
  // Knob at 0.1 (0x0f), axis X (0x11), wheel still; byte 1 and 7 as a pendant varies them.
  const std::vector<Case> cases = {
      {{0x04, 0x82, 0x01, 0x00, 0x0f, 0x11, 0x00, 0x81}, Key::Reset},
      {{0x04, 0x33, 0x02, 0x00, 0x0f, 0x11, 0x00, 0x31}, Key::Stop},
      {{0x04, 0x47, 0x03, 0x00, 0x0f, 0x11, 0x00, 0x45}, Key::StartPause},
      {{0x04, 0x10, 0x04, 0x00, 0x0f, 0x11, 0x00, 0x0c}, Key::FeedPlus},
      {{0x04, 0x10, 0x05, 0x00, 0x0f, 0x11, 0x00, 0x0b}, Key::FeedMinus},
      {{0x04, 0x10, 0x06, 0x00, 0x0f, 0x11, 0x00, 0x0a}, Key::SpindlePlus},
      {{0x04, 0x10, 0x07, 0x00, 0x0f, 0x11, 0x00, 0x09}, Key::SpindleMinus},
      {{0x04, 0x10, 0x08, 0x00, 0x0f, 0x11, 0x00, 0x08}, Key::MachineHome},
      {{0x04, 0x10, 0x09, 0x00, 0x0f, 0x11, 0x00, 0x07}, Key::SafeZ},
      {{0x04, 0x10, 0x0a, 0x00, 0x0f, 0x11, 0x00, 0x06}, Key::WorkHome},
      {{0x04, 0x10, 0x0b, 0x00, 0x0f, 0x11, 0x00, 0x05}, Key::SpindleOnOff},
      {{0x04, 0x10, 0x0c, 0x00, 0x0f, 0x11, 0x00, 0x04}, Key::Fn},
      {{0x04, 0x10, 0x0d, 0x00, 0x0f, 0x11, 0x00, 0x03}, Key::ProbeZ},
      {{0x04, 0x10, 0x0e, 0x00, 0x0f, 0x11, 0x00, 0x02}, Key::Continuous},
      {{0x04, 0x10, 0x0f, 0x00, 0x0f, 0x11, 0x00, 0x01}, Key::Step},
      {{0x04, 0x10, 0x10, 0x00, 0x0f, 0x11, 0x00, 0x00}, Key::Macro10},
  };
  for (const auto& c : cases) {
    const auto r = decoded(c.bytes);
    EXPECT_EQ(r.kind, ReportKind::Input);
    EXPECT_EQ(r.key1, c.key) << to_string(c.key);
    EXPECT_EQ(r.key2, Key::None);
    EXPECT_EQ(r.fn, c.key == Key::Fn) << to_string(c.key);
    EXPECT_EQ(r.wheel, 0);
  }
}

TEST(Whb04bReport, FnWithEachKeyIsItsMacro) {
  struct Case {
    std::uint8_t code;
    int macro;
  };
  // The numbers printed on the pendant (1-9) and LinuxCNC's extension (11-16).
  const std::vector<Case> cases = {{0x04, 1},  {0x05, 2},  {0x06, 3},  {0x07, 4},  {0x08, 5},  {0x09, 6},
                                   {0x0a, 7},  {0x0b, 8},  {0x0d, 9},  {0x01, 11}, {0x02, 12}, {0x03, 13},
                                   {0x10, 14}, {0x0e, 15}, {0x0f, 16}};
  for (const auto& c : cases) {
    const auto r = decoded({0x04, 0x5e, 0x0c, c.code, 0x0e, 0x12, 0x00, 0x5c});
    EXPECT_TRUE(r.fn);
    EXPECT_EQ(r.key1, Key::Fn);
    EXPECT_EQ(static_cast<std::uint8_t>(r.key2), c.code);
    EXPECT_EQ(fn_macro_number(r.key2), c.macro) << to_string(r.key2);
  }
  // Fn second: the same macro.
  const auto r = decoded({0x04, 0x5e, 0x0a, 0x0c, 0x0e, 0x12, 0x00, 0x5c});
  EXPECT_TRUE(r.fn);
  EXPECT_EQ(r.key1, Key::WorkHome);
  EXPECT_EQ(fn_macro_number(Key::Fn), 0);
  EXPECT_EQ(fn_macro_number(Key::None), 0);
}

TEST(Whb04bReport, EveryAxisPosition) {
  const std::vector<std::pair<std::uint8_t, AxisKnob>> cases = {
      {0x06, AxisKnob::Off}, {0x11, AxisKnob::X}, {0x12, AxisKnob::Y}, {0x13, AxisKnob::Z},
      {0x14, AxisKnob::A},   {0x15, AxisKnob::B}, {0x16, AxisKnob::C}};
  for (const auto& [code, axis] : cases) {
    const auto r = decoded({0x04, 0xba, 0x00, 0x00, 0x0e, code, 0x00, 0xba});
    EXPECT_EQ(r.axis, axis) << int(code);
  }
  EXPECT_EQ(axis_index(AxisKnob::X), 0);
  EXPECT_EQ(axis_index(AxisKnob::Y), 1);
  EXPECT_EQ(axis_index(AxisKnob::Z), 2);
  EXPECT_FALSE(axis_index(AxisKnob::A));
  EXPECT_FALSE(axis_index(AxisKnob::Off));
}

TEST(Whb04bReport, EveryFeedKnobPositionWithItsStepAndPercent) {
  struct Case {
    std::uint8_t code;
    FeedKnob knob;
    std::optional<double> step;
    std::optional<int> percent;
  };
  const std::vector<Case> cases = {
      {0x0d, FeedKnob::Step0001, 0.001, 2}, {0x0e, FeedKnob::Step001, 0.01, 5},
      {0x0f, FeedKnob::Step01, 0.1, 10},    {0x10, FeedKnob::Step1, 1.0, 30},
      {0x1a, FeedKnob::Percent60, {}, 60},  {0x1b, FeedKnob::Percent100, {}, 100},
      {0x1c, FeedKnob::Lead, {}, {}},       {0x9b, FeedKnob::Lead, {}, {}},
  };
  for (const auto& c : cases) {
    const auto r = decoded({0x04, 0x21, 0x00, 0x00, c.code, 0x13, 0x00, 0x21});
    EXPECT_EQ(r.feed_knob, c.knob) << int(c.code);
    EXPECT_EQ(knob_step_mm(r.feed_knob), c.step) << int(c.code);
    EXPECT_EQ(knob_percent(r.feed_knob), c.percent) << int(c.code);
  }
}

TEST(Whb04bReport, WheelCountIsSigned) {
  EXPECT_EQ(decoded({0x04, 0x9d, 0x00, 0x00, 0x0e, 0x12, 0x01, 0x9c}).wheel, 1);
  EXPECT_EQ(decoded({0x04, 0x9d, 0x00, 0x00, 0x0e, 0x12, 0x05, 0x9c}).wheel, 5);
  EXPECT_EQ(decoded({0x04, 0x9d, 0x00, 0x00, 0x0e, 0x12, 0xff, 0x9c}).wheel, -1);
  EXPECT_EQ(decoded({0x04, 0x9d, 0x00, 0x00, 0x0e, 0x12, 0xf6, 0x9c}).wheel, -10);
  EXPECT_EQ(decoded({0x04, 0x9d, 0x00, 0x00, 0x0e, 0x12, 0x81, 0x9c}).wheel, -127);
}

TEST(Whb04bReport, SleepAndIdleReports) {
  EXPECT_EQ(decoded({0x04, 0xff, 0xff, 0xff, 0xff, 0xff, 0x81, 0xff}).kind, ReportKind::Sleeping);
  EXPECT_EQ(decoded({0x04, 0x6a, 0x00, 0x00, 0x00, 0x00, 0x00, 0x6a}).kind, ReportKind::Idle);
  EXPECT_EQ(decoded({0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}).kind, ReportKind::Idle);
}

TEST(Whb04bReport, BytesNoPendantSendsNameTheByte) {
  EXPECT_EQ(decode_error({0x05, 0x00, 0x00, 0x00, 0x0e, 0x11, 0x00, 0x00}),
            "byte 0 (report id) is 0x05: expected 0x04");
  EXPECT_EQ(decode_error({0x04, 0x00, 0x11, 0x00, 0x0e, 0x11, 0x00, 0x00}),
            "byte 2 (key 1) is 0x11: expected a key code 0x00-0x10");
  EXPECT_EQ(decode_error({0x04, 0x00, 0x00, 0x2a, 0x0e, 0x11, 0x00, 0x00}),
            "byte 3 (key 2) is 0x2a: expected a key code 0x00-0x10");
  EXPECT_NE(decode_error({0x04, 0x00, 0x00, 0x00, 0x20, 0x11, 0x00, 0x00}).find("byte 4 (feed knob) is 0x20"),
            std::string::npos);
  EXPECT_NE(decode_error({0x04, 0x00, 0x00, 0x00, 0x0e, 0x07, 0x00, 0x00}).find("byte 5 (axis knob) is 0x07"),
            std::string::npos);
  // Eight zero bytes are the idle report, but zero keys and knobs under another id are not.
  EXPECT_NE(decode_error({0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}).find("byte 0"), std::string::npos);
}

TEST(Whb04bTracker, KnobsKeysWheelSleepAndWake) {
  PendantInputTracker t;
  auto feed = [&](const InputReport& b) { return t.update(decoded(b)); };

  // The first report tells the knob positions.
  auto ev = feed({0x04, 0xba, 0x00, 0x00, 0x0f, 0x11, 0x00, 0xba});
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::AxisChanged);
  EXPECT_EQ(ev[0].axis, AxisKnob::X);
  EXPECT_EQ(ev[1].kind, PendantEventKind::KnobChanged);
  EXPECT_EQ(ev[1].knob, FeedKnob::Step01);

  // The same report again: nothing happened.
  EXPECT_TRUE(feed({0x04, 0x3b, 0x00, 0x00, 0x0f, 0x11, 0x00, 0x3a}).empty());

  ev = feed({0x04, 0x82, 0x01, 0x00, 0x0f, 0x11, 0x00, 0x81});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::KeyPressed);
  EXPECT_EQ(ev[0].key, Key::Reset);
  EXPECT_FALSE(ev[0].fn);
  EXPECT_TRUE(t.key_down(Key::Reset));
  // Held: a wheel report while Reset stays down is not a second press.
  ev = feed({0x04, 0x82, 0x01, 0x00, 0x0f, 0x11, 0x02, 0x81});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::Wheel);
  ev = feed({0x04, 0xbd, 0x00, 0x00, 0x0f, 0x11, 0x00, 0xbc});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::KeyReleased);
  EXPECT_EQ(ev[0].key, Key::Reset);

  // Fn, then W-Home with Fn held: macro 7.
  ev = feed({0x04, 0x10, 0x0c, 0x00, 0x0f, 0x11, 0x00, 0x10});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].key, Key::Fn);
  ev = feed({0x04, 0x10, 0x0c, 0x0a, 0x0f, 0x11, 0x00, 0x10});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::KeyPressed);
  EXPECT_EQ(ev[0].key, Key::WorkHome);
  EXPECT_TRUE(ev[0].fn);
  ev = feed({0x04, 0x10, 0x00, 0x00, 0x0f, 0x11, 0x00, 0x10});
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::KeyReleased);
  EXPECT_EQ(ev[1].kind, PendantEventKind::KeyReleased);

  // Axis to Y and the wheel back three detents in one report: the wheel event carries the new axis.
  ev = feed({0x04, 0x10, 0x00, 0x00, 0x0f, 0x12, 0xfd, 0x10});
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::AxisChanged);
  EXPECT_EQ(ev[0].axis, AxisKnob::Y);
  EXPECT_EQ(ev[1].kind, PendantEventKind::Wheel);
  EXPECT_EQ(ev[1].detents, -3);
  EXPECT_EQ(ev[1].axis, AxisKnob::Y);
  EXPECT_EQ(ev[1].knob, FeedKnob::Step01);

  // Knob to 100 %.
  ev = feed({0x04, 0x10, 0x00, 0x00, 0x1b, 0x12, 0x00, 0x10});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::KnobChanged);
  EXPECT_EQ(ev[0].knob, FeedKnob::Percent100);

  // Sleep: the idle report, then the sleep report; one Sleep event.
  ev = feed({0x04, 0x6a, 0x00, 0x00, 0x00, 0x00, 0x00, 0x6a});
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::Sleep);
  EXPECT_TRUE(t.sleeping());
  EXPECT_TRUE(feed({0x04, 0xff, 0xff, 0xff, 0xff, 0xff, 0x81, 0xff}).empty());

  // Wake: the knob moved while asleep.
  ev = feed({0x04, 0x77, 0x00, 0x00, 0x0d, 0x12, 0x00, 0x77});
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::Wake);
  EXPECT_EQ(ev[1].kind, PendantEventKind::KnobChanged);
  EXPECT_EQ(ev[1].knob, FeedKnob::Step0001);
  EXPECT_FALSE(t.sleeping());
}

TEST(Whb04bTracker, SleepWhileAKeyIsDownForgetsIt) {
  PendantInputTracker t;
  t.update(decoded({0x04, 0x10, 0x02, 0x00, 0x0f, 0x11, 0x00, 0x10}));
  EXPECT_TRUE(t.key_down(Key::Stop));
  t.update(decoded({0x04, 0xff, 0xff, 0xff, 0xff, 0xff, 0x81, 0xff}));
  EXPECT_FALSE(t.key_down(Key::Stop));
  // Stop down again after the wake is a new press.
  const auto ev = t.update(decoded({0x04, 0x10, 0x02, 0x00, 0x0f, 0x11, 0x00, 0x10}));
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, PendantEventKind::Wake);
  EXPECT_EQ(ev[1].kind, PendantEventKind::KeyPressed);
  EXPECT_EQ(ev[1].key, Key::Stop);
}
