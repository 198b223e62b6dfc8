#include "cncstream/gcode/program_extent.hpp"

#include <algorithm>
#include <variant>

#include "cncstream/gcode/arc_segments.hpp"
#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"

namespace cncstream::gcode {

namespace {

// What a line says beyond its actions: its axis words, and whether its
// move goes somewhere not relative to the work.
struct LineWords {
  std::array<bool, 3> axis{};
  bool machine_target = false;  // G53, G28, G30 (not G28.1/G30.1)
  bool g53 = false;
};

LineWords line_words(const std::string& cleaned) {
  LineWords w;
  const LexResult lex = lex_words(cleaned);
  for (const Word& word : lex.words) {
    if (word.letter == 'X') w.axis[0] = true;
    else if (word.letter == 'Y') w.axis[1] = true;
    else if (word.letter == 'Z') w.axis[2] = true;
    else if (word.letter == 'G' && (word.value == 53 || word.value == 28 || word.value == 30)) {
      w.machine_target = true;
      if (word.value == 53) w.g53 = true;
    }
  }
  return w;
}

// One axis: the positions since the current coordinate system was selected,
// and the largest measure of the earlier ones.
struct AxisRun {
  bool known = false;  // the position on this axis is known in the current frame
  AxisExtent run, best;
  void add(double v) {
    if (!run.known) run = {v, v, true};
    run.lo = std::min(run.lo, v);
    run.hi = std::max(run.hi, v);
  }
  void close() {
    if (run.known && (!best.known || run.size() > best.size())) best = run;
    run = {};
  }
};

}  // namespace

ProgramExtent program_extent(const std::vector<std::string>& lines, double arc_tolerance) {
  std::array<AxisRun, 3> axes;
  HullAccumulator run_hull;
  std::vector<XyPoint> best_hull;
  // The hull follows the X measure: kept from the frame whose X run wins.
  const auto close_hull = [&] {
    const AxisRun& x = axes[0];
    if (x.run.known && (!x.best.known || x.run.size() > x.best.size())) best_hull = run_hull.hull();
    run_hull = HullAccumulator{};
  };
  const auto add_xy = [&](double px, double py) {
    if (axes[0].known && axes[1].known) run_hull.add(px, py);
  };
  ParserState state;
  for (const std::string& raw : lines) {
    const CleanLine c = clean_line(raw);
    if (c.overflow || c.text.empty() || c.text == "%" || c.text.front() == '$') continue;
    const BlockResult r = execute_block(state, c.text);
    if (!r.ok()) continue;
    if (r.state.modal.coord_select != state.modal.coord_select) {
      close_hull();
      for (AxisRun& a : axes) {
        a.close();
        a.known = false;
      }
    }
    const LineWords words = line_words(c.text);
    bool moved = false, probed = false;
    for (const Action& action : r.actions) {
      if (std::holds_alternative<LinearMove>(action) || std::holds_alternative<ArcMove>(action)) moved = true;
      if (std::holds_alternative<ProbeMove>(action)) probed = true;
    }
    if (words.machine_target && moved) {
      // G28/G30 end at a stored position on every axis; G53 on the axes it names.
      for (int i = 0; i < 3; ++i)
        if (!words.g53 || words.axis[i]) axes[i].known = false;
    } else if (probed) {
      for (int i = 0; i < 3; ++i)
        if (words.axis[i]) axes[i].known = false;  // it stops where it touches
    } else if (moved) {
      std::array<bool, 3> known_before{};
      for (int i = 0; i < 3; ++i) {
        known_before[i] = axes[i].known;
        if (words.axis[i] && !r.state.modal.incremental) axes[i].known = true;
      }
      for (const Action& action : r.actions) {
        if (const auto* m = std::get_if<LinearMove>(&action)) {
          for (int i = 0; i < 3; ++i)
            if (axes[i].known) axes[i].add(component(m->to, i));
          add_xy(m->to.x, m->to.y);
        } else if (const auto* arc = std::get_if<ArcMove>(&action)) {
          // Its chords need a known start as well as a known end.
          for (const geometry::Vec3& p : arc_chords(*arc, arc_tolerance).points) {
            for (int i = 0; i < 3; ++i)
              if (axes[i].known && known_before[i]) axes[i].add(component(p, i));
            if (known_before[0] && known_before[1]) add_xy(p.x, p.y);
          }
          for (int i = 0; i < 3; ++i)
            if (axes[i].known) axes[i].add(component(arc->to, i));
          add_xy(arc->to.x, arc->to.y);
        }
      }
    }
    state = r.state;
  }
  ProgramExtent e;
  close_hull();
  e.xy_hull = std::move(best_hull);
  for (int i = 0; i < 3; ++i) {
    axes[i].close();
    e.axes[i] = axes[i].best;
  }
  return e;
}

}  // namespace cncstream::gcode
