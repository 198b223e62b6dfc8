// The terminal jog mode's pure parts: bytes + arrival times -> keys, keys +
// time -> jog intents (tap, hold, release), and the DRO line. Every sequence
// is scripted with explicit times, so no test sleeps.
#include <gtest/gtest.h>

#include "jog_control.hpp"
#include "jog_display.hpp"
#include "terminal_keys.hpp"

using namespace cncstream::app;

namespace {

std::vector<Key> keys_of(const std::vector<KeyEvent>& ev) {
  std::vector<Key> k;
  for (const auto& e : ev) k.push_back(e.key);
  return k;
}

KeyEvent press(Key k, double at) { return {k, 0, at}; }
KeyEvent chr(char c, double at) { return {Key::Char, c, at}; }

JogIntent step(JogKey k) { return {JogIntentKind::Step, k}; }
JogIntent start(JogKey k) { return {JogIntentKind::Start, k}; }
JogIntent renew(JogKey k) { return {JogIntentKind::Renew, k}; }
JogIntent release(JogKey k) { return {JogIntentKind::Release, k}; }
using Intents = std::vector<JogIntent>;

}  // namespace

// ---- KeyDecoder -------------------------------------------------------------

TEST(KeyDecoder, ArrowsInBothCursorModesPageKeysAndPlainKeys) {
  KeyDecoder d;
  EXPECT_EQ(keys_of(d.feed("\x1b[A\x1b[B\x1b[C\x1b[D", 1.0)),
            (std::vector<Key>{Key::Up, Key::Down, Key::Right, Key::Left}));
  EXPECT_EQ(keys_of(d.feed("\x1bOA\x1bOB\x1bOC\x1bOD", 1.1)),
            (std::vector<Key>{Key::Up, Key::Down, Key::Right, Key::Left}));
  EXPECT_EQ(keys_of(d.feed("\x1b[5~\x1b[6~", 1.2)), (std::vector<Key>{Key::PageUp, Key::PageDown}));
  const auto plain = d.feed("q0 ", 1.3);
  ASSERT_EQ(plain.size(), 3u);
  EXPECT_EQ(plain[0], chr('q', 1.3));
  EXPECT_EQ(plain[1], chr('0', 1.3));
  EXPECT_EQ(plain[2], chr(' ', 1.3));
  EXPECT_FALSE(d.deadline());
}

TEST(KeyDecoder, ASequenceSplitAcrossReadsIsOneKeyTimedAtItsLastByte) {
  KeyDecoder d;
  EXPECT_TRUE(d.feed("\x1b", 2.0).empty());
  ASSERT_TRUE(d.deadline());
  EXPECT_DOUBLE_EQ(*d.deadline(), 2.0 + KeyDecoder::kDefaultEscTimeout_s);
  EXPECT_TRUE(d.feed("[", 2.01).empty());
  const auto k = d.feed("C", 2.02);
  ASSERT_EQ(k.size(), 1u);
  EXPECT_EQ(k[0], press(Key::Right, 2.02));
  EXPECT_TRUE(d.feed("\x1b[6", 3.0).empty());
  EXPECT_EQ(keys_of(d.feed("~", 3.001)), std::vector<Key>{Key::PageDown});
}

TEST(KeyDecoder, ALoneEscapeIsAKeyOnlyAfterItsTimeout) {
  KeyDecoder d(0.05);
  EXPECT_TRUE(d.feed("\x1b", 1.0).empty());
  EXPECT_FALSE(d.expire(1.049));  // a sequence may still follow
  const auto esc = d.expire(1.05);
  ASSERT_TRUE(esc);
  EXPECT_EQ(*esc, press(Key::Escape, 1.0));
  EXPECT_FALSE(d.deadline());
  // Resolved by the next read too, when the timer was late.
  d.feed("\x1b", 2.0);
  EXPECT_EQ(keys_of(d.feed("q", 2.5)), (std::vector<Key>{Key::Escape, Key::Char}));
  // ESC ESC [ A: the first is a key of its own, the rest an arrow.
  EXPECT_EQ(keys_of(d.feed("\x1b\x1b[A", 3.0)), (std::vector<Key>{Key::Escape, Key::Up}));
}

TEST(KeyDecoder, GarbageSequencesBecomeUnknownAndNeverEatTheNextKeys) {
  KeyDecoder d;
  // Function key, modified arrow, Home, Alt+x: not ours.
  EXPECT_EQ(keys_of(d.feed("\x1b[15~\x1b[1;5C\x1b[H\x1bx", 1.0)),
            (std::vector<Key>{Key::Unknown, Key::Unknown, Key::Unknown, Key::Unknown}));
  // An SS3 with a bad final, then q.
  EXPECT_EQ(keys_of(d.feed("\x1bO\x01q", 1.1)), (std::vector<Key>{Key::Unknown, Key::Char, Key::Char}));
  // A CSI cut short by a control byte: the byte and what follows still count.
  const auto cut = d.feed("\x1b[5\rq", 1.2);
  ASSERT_EQ(keys_of(cut), (std::vector<Key>{Key::Unknown, Key::Char, Key::Char}));
  EXPECT_EQ(cut[1].ch, '\r');
  EXPECT_EQ(cut[2].ch, 'q');
  // An endless parameter string is cut at the length limit.
  std::string endless = "\x1b[";
  endless.append(40, '1');
  endless += "A";
  const auto long_seq = d.feed(endless, 1.3);
  ASSERT_GE(long_seq.size(), 1u);
  EXPECT_EQ(long_seq[0].key, Key::Unknown);
  for (const auto& k : long_seq) EXPECT_NE(k.key, Key::Up);
  // An unfinished CSI times out as Unknown, not as Escape.
  d.feed("\x1b[", 2.0);
  const auto late = d.expire(2.1);
  ASSERT_TRUE(late);
  EXPECT_EQ(late->key, Key::Unknown);
  EXPECT_EQ(keys_of(d.feed("\x1b[C", 2.2)), std::vector<Key>{Key::Right});
}

// ---- HeldKeyDetector ----------------------------------------------------------

TEST(HeldKeyDetector, TapsAreStepsEvenWhenQuick) {
  HeldKeyDetector h;
  EXPECT_EQ(h.on_key(press(Key::Right, 1.0)), Intents{step(JogKey::XPlus)});
  // A double tap 150 ms apart: two steps, no continuous jog.
  EXPECT_EQ(h.on_key(press(Key::Right, 1.15)), Intents{step(JogKey::XPlus)});
  EXPECT_FALSE(h.holding());
  // A third tap 150 ms later: a person, not auto-repeat (slower than 100 ms).
  EXPECT_EQ(h.on_key(press(Key::Right, 1.30)), Intents{step(JogKey::XPlus)});
  EXPECT_EQ(h.on_key(press(Key::Right, 3.0)), Intents{step(JogKey::XPlus)});
  EXPECT_FALSE(h.holding());
  EXPECT_FALSE(h.deadline());
  EXPECT_FALSE(h.tick(10.0));
}

TEST(HeldKeyDetector, AHeldKeyStepsThenJogsUntilItsRepeatsStop) {
  HeldKeyDetector h;  // X11-like: first repeat after 500 ms, then every 40 ms
  EXPECT_EQ(h.on_key(press(Key::Up, 0.0)), Intents{step(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Up, 0.5)), Intents{step(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Up, 0.54)), Intents{start(JogKey::YPlus)});
  EXPECT_TRUE(h.holding());
  EXPECT_NEAR(h.lease_s(), 0.1, 1e-9);  // 2.5 x 40 ms
  double t = 0.54;
  for (int i = 0; i < 20; ++i) {
    t += 0.04;
    EXPECT_FALSE(h.tick(t - 0.001));
    EXPECT_EQ(h.on_key(press(Key::Up, t)), Intents{renew(JogKey::YPlus)});
  }
  EXPECT_NEAR(h.repeat_period_s(), 0.04, 1e-9);
  // Released after the last repeat at t: noticed at t + lease, never later than 100 ms.
  ASSERT_TRUE(h.deadline());
  EXPECT_LE(*h.deadline() - t, 0.1 + 1e-9);
  EXPECT_FALSE(h.tick(*h.deadline() - 0.001));
  EXPECT_EQ(h.tick(*h.deadline()), release(JogKey::YPlus));
  EXPECT_FALSE(h.holding());
  EXPECT_FALSE(h.tick(t + 1));  // once
  // Pressed again a second later: a step again.
  EXPECT_EQ(h.on_key(press(Key::Up, t + 1)), Intents{step(JogKey::YPlus)});
}

TEST(HeldKeyDetector, TheLeaseFollowsTheRepeatPeriodWithinItsBounds) {
  HeldKeyTiming timing;
  {
    HeldKeyDetector fast(timing);  // 15 ms repeats: lease at its floor
    fast.on_key(press(Key::Left, 0));
    fast.on_key(press(Key::Left, 0.25));
    fast.on_key(press(Key::Left, 0.265));
    ASSERT_TRUE(fast.holding());
    EXPECT_NEAR(fast.lease_s(), timing.min_lease_s, 1e-9);
  }
  {
    HeldKeyDetector mid(timing);  // 30 ms repeats: 75 ms
    mid.on_key(press(Key::Left, 0));
    mid.on_key(press(Key::Left, 0.6));
    mid.on_key(press(Key::Left, 0.63));
    ASSERT_TRUE(mid.holding());
    EXPECT_NEAR(mid.lease_s(), 0.075, 1e-9);
    EXPECT_NEAR(*mid.deadline(), 0.63 + 0.075, 1e-9);
  }
  {
    HeldKeyDetector slow(timing);  // 90 ms repeats: capped at 100 ms
    slow.on_key(press(Key::Left, 0));
    slow.on_key(press(Key::Left, 0.6));
    slow.on_key(press(Key::Left, 0.69));
    ASSERT_TRUE(slow.holding());
    EXPECT_NEAR(slow.lease_s(), timing.max_lease_s, 1e-9);
  }
}

TEST(HeldKeyDetector, AnotherKeyReleasesFirstThenActs) {
  HeldKeyDetector h;
  h.on_key(press(Key::Right, 0));
  h.on_key(press(Key::Right, 0.5));
  ASSERT_EQ(h.on_key(press(Key::Right, 0.53)), Intents{start(JogKey::XPlus)});
  // Holding Right, then Up pressed: the terminal repeats Up from now on.
  EXPECT_EQ(h.on_key(press(Key::Up, 0.56)), (Intents{release(JogKey::XPlus), step(JogKey::YPlus)}));
  EXPECT_FALSE(h.holding());
  EXPECT_EQ(h.on_key(press(Key::Up, 1.0)), Intents{step(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Up, 1.03)), Intents{start(JogKey::YPlus)});
  // Any non-jog key (space, q, Esc, an unknown sequence) releases.
  EXPECT_EQ(h.on_key(chr(' ', 1.05)), Intents{release(JogKey::YPlus)});
  EXPECT_FALSE(h.holding());
  EXPECT_FALSE(h.deadline());
  // And breaks a repeat chain: the next Up is a fresh tap.
  EXPECT_EQ(h.on_key(press(Key::Up, 1.07)), Intents{step(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Up, 1.09)), Intents{step(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Up, 1.12)), Intents{start(JogKey::YPlus)});
  EXPECT_EQ(h.on_key(press(Key::Escape, 1.15)), Intents{release(JogKey::YPlus)});
  EXPECT_TRUE(h.on_key(press(Key::Unknown, 1.2)).empty());
}

TEST(HeldKeyDetector, TwoKeysAlternatingAreStepsOfEach) {
  HeldKeyDetector h;
  EXPECT_EQ(h.on_key(press(Key::PageUp, 0)), Intents{step(JogKey::ZPlus)});
  EXPECT_EQ(h.on_key(press(Key::PageDown, 0.03)), Intents{step(JogKey::ZMinus)});
  EXPECT_EQ(h.on_key(press(Key::PageUp, 0.06)), Intents{step(JogKey::ZPlus)});
  EXPECT_EQ(h.on_key(press(Key::PageDown, 0.09)), Intents{step(JogKey::ZMinus)});
  EXPECT_FALSE(h.holding());
}

TEST(HeldKeyDetector, PressesReadTogetherAreStepsNotARepeat) {
  HeldKeyDetector h;
  // Typed ahead or pasted: three in one read (one arrival time).
  EXPECT_EQ(h.on_key(press(Key::Right, 1.0)), Intents{step(JogKey::XPlus)});
  EXPECT_EQ(h.on_key(press(Key::Right, 1.0)), Intents{step(JogKey::XPlus)});
  EXPECT_EQ(h.on_key(press(Key::Right, 1.0)), Intents{step(JogKey::XPlus)});
  EXPECT_FALSE(h.holding());
}

TEST(HeldKeyDetector, ALateRepeatEndsTheJogAndTheNextRepeatRestartsIt) {
  HeldKeyDetector h;
  h.on_key(press(Key::Down, 0));
  h.on_key(press(Key::Down, 0.5));
  ASSERT_EQ(h.on_key(press(Key::Down, 0.54)), Intents{start(JogKey::YMinus)});
  // A busy machine delays a repeat past the lease: the lease wins (the
  // release comes first, from the key's own processing if no timer ran).
  EXPECT_EQ(h.on_key(press(Key::Down, 0.8)), (Intents{release(JogKey::YMinus), step(JogKey::YMinus)}));
  EXPECT_FALSE(h.holding());
  EXPECT_EQ(h.on_key(press(Key::Down, 0.83)), Intents{start(JogKey::YMinus)});
  ASSERT_NEAR(h.lease_s(), 0.075, 1e-9);  // 30 ms repeats
  // Lapsed by the timer, then the repeat comes 15 ms later (90 ms after the
  // one before, still faster than a person): jogging again, no step.
  ASSERT_EQ(h.tick(0.83 + 0.075), release(JogKey::YMinus));
  EXPECT_EQ(h.on_key(press(Key::Down, 0.92)), Intents{start(JogKey::YMinus)});
  // Lapsed, and the next press 150 ms after the last: a person's tap, a step.
  ASSERT_TRUE(h.tick(0.92 + h.lease_s()));
  EXPECT_EQ(h.on_key(press(Key::Down, 1.07)), Intents{step(JogKey::YMinus)});
  h.reset();
  EXPECT_FALSE(h.holding());
  EXPECT_FALSE(h.deadline());
  EXPECT_EQ(h.on_key(press(Key::Down, 1.5)), Intents{step(JogKey::YMinus)});
}

TEST(HeldKeyDetector, DecodedBytesEndToEnd) {
  // A held Right as a terminal sends it: ESC [ C, the first repeat after
  // 400 ms, then every 33 ms; released after 1 s.
  KeyDecoder d;
  HeldKeyDetector h;
  Intents all;
  auto feed = [&](double t) {
    for (const auto& k : d.feed("\x1b[C", t))
      for (const auto& i : h.on_key(k)) all.push_back(i);
  };
  feed(0);
  double t = 0.4;
  for (; t < 1.0; t += 0.033) feed(t);
  const double last = t - 0.033;
  ASSERT_TRUE(h.deadline());
  const double released_at = *h.deadline();
  all.push_back(*h.tick(released_at));
  EXPECT_LE(released_at - last, 0.1 + 1e-9);
  ASSERT_GE(all.size(), 4u);
  EXPECT_EQ(all[0], step(JogKey::XPlus));
  EXPECT_EQ(all[1], step(JogKey::XPlus));
  EXPECT_EQ(all[2], start(JogKey::XPlus));
  for (std::size_t i = 3; i + 1 < all.size(); ++i) EXPECT_EQ(all[i], renew(JogKey::XPlus));
  EXPECT_EQ(all.back(), release(JogKey::XPlus));
}

// ---- feed ladder and DRO ----------------------------------------------------------

TEST(JogFeed, DefaultAndLadder) {
  EXPECT_EQ(default_jog_feed(0), 1000);  // not known yet
  EXPECT_EQ(default_jog_feed(500), 500);
  EXPECT_EQ(default_jog_feed(3000), 1000);
  EXPECT_EQ(next_jog_feed(500, +1, 0), 1000);
  EXPECT_EQ(next_jog_feed(500, -1, 0), 200);
  EXPECT_EQ(next_jog_feed(700, +1, 0), 1000);
  EXPECT_EQ(next_jog_feed(700, -1, 0), 500);
  EXPECT_EQ(next_jog_feed(10, -1, 0), 10);
  EXPECT_EQ(next_jog_feed(1000, +1, 1500), 1500);
}

TEST(JogDisplay, DroLineShowsStatePositionsStepFeedJogAndMessage) {
  DroView v;
  v.link = "ready";
  v.state = "Jog";
  v.wpos = cncstream::protocol::Axes{1.5, -2, 0.25, 0, 0, 0};
  v.mpos = cncstream::protocol::Axes{11.5, 8, -4.75, 0, 0, 0};
  v.step_mm = 0.01;
  v.feed_mm_min = 1000;
  v.jog = "X+ held";
  v.message = "refused: jog: a job is running";
  const std::string line = format_dro_line(v);
  EXPECT_EQ(line,
            "Jog | WPos X   1.500 Y  -2.000 Z   0.250 | MPos X  11.500 Y   8.000 Z  -4.750 | step 0.01 mm | "
            "feed 1000 mm/min | X+ held | refused: jog: a job is running");
  const std::string cut = format_dro_line(v, 40);
  EXPECT_EQ(cut.size(), 40u);
  EXPECT_EQ(cut.substr(37), "...");
  v.link = "disconnected";
  v.wpos.reset();
  v.jog.clear();
  EXPECT_EQ(format_dro_line(v).rfind("disconnected | WPos X       - Y       - Z       - |", 0), 0u);
}
