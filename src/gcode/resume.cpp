#include "cncstream/gcode/resume.hpp"

#include <algorithm>
#include <sstream>

#include "cncstream/gcode/gcode_writer.hpp"

namespace cncstream::gcode {

namespace {
std::string num(double v) { return format_gcode_number(v, 4); }
}  // namespace

std::vector<std::string> resume_preamble(const ParserState& at, const ResumeOptions& o) {
  const ModalState& m = at.modal;
  std::vector<std::string> out;
  std::ostringstream l;
  auto emit = [&] {
    out.push_back(l.str());
    l.str({});
  };
  const geometry::Vec3 p = at.work_position();  // where the tool was, in the program's work coordinates
  const geometry::Vec3 g92 = at.g92;
  const double safe = std::max(o.safe_z, p.z);
  l << "G21 G90 G94 G17";
  emit();
  if (o.machine_safe_z) {
    l << "G53 G0 Z" << num(*o.machine_safe_z);
    emit();
  }
  l << "G" << 54 + m.coord_select;
  emit();
  // A reset clears G92; moves go in WCS-only coordinates (work + G92) until
  // G92 is set again from the known position.
  l << "G92.1";
  emit();
  if (m.tool_length_dynamic) l << "G43.1 Z" << num(at.tool_length_offset);
  else l << "G49";
  emit();
  l << "G0 Z" << num(safe + g92.z);
  emit();
  l << "G0 X" << num(p.x + g92.x) << " Y" << num(p.y + g92.y);
  emit();
  if (g92 != geometry::Vec3{}) {
    l << "G92 X" << num(p.x) << " Y" << num(p.y) << " Z" << num(safe);
    emit();
  }
  if (m.spindle != SpindleState::Off) l << (m.spindle == SpindleState::CW ? "M3" : "M4") << " S" << num(at.spindle_speed);
  else l << "M5";
  emit();
  if (m.mist) {
    l << "M7";
    emit();
  }
  if (m.flood) {
    l << "M8";
    emit();
  }
  if (!m.mist && !m.flood) {
    l << "M9";
    emit();
  }
  if ((m.spindle != SpindleState::Off || m.mist || m.flood) && o.dwell_s > 0) {
    l << "G4 P" << num(o.dwell_s);
    emit();
  }
  if (p.z < safe) {
    l << "G1 Z" << num(p.z) << " F" << num(o.plunge_feed);
    emit();
  }
  // The program's own modes last (its units change how F reads).
  const char* plane = m.plane == Plane::XY ? "G17" : m.plane == Plane::ZX ? "G18" : "G19";
  l << (m.inches ? "G20" : "G21") << " " << (m.incremental ? "G91" : "G90") << " " << plane << " "
    << (m.inverse_time ? "G93" : "G94");
  emit();
  if (!m.inverse_time && at.feed_rate > 0) {
    l << "F" << num(m.inches ? at.feed_rate / kMmPerInch : at.feed_rate);
    emit();
  }
  switch (m.motion) {
    case MotionMode::Rapid: l << "G0"; break;
    case MotionMode::Linear: l << "G1"; break;
    case MotionMode::None: l << "G80"; break;
    default: break;  // arcs: with_modal_arc; probing is never modal across lines in practice
  }
  if (!l.str().empty()) emit();
  return out;
}

std::optional<ModalArcFix> with_modal_arc(std::span<const std::string> lines_after, MotionMode mode) {
  if (mode != MotionMode::ArcCW && mode != MotionMode::ArcCCW) return std::nullopt;
  for (std::size_t i = 0; i < lines_after.size(); ++i) {
    const CleanLine clean = clean_line(lines_after[i]);
    const LexResult lex = lex_words(clean.text);
    if (lex.status != 0) return std::nullopt;  // the controller rejects it anyway
    bool axis = false, names_motion = false, non_modal_axes = false;
    for (const Word& w : lex.words) {
      if (w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z') axis = true;
      if (w.letter != 'G') continue;
      const double g = w.value;
      if (g == 0 || g == 1 || g == 2 || g == 3 || g == 80 || (g > 38 && g < 39)) names_motion = true;
      // G10, G28, G30, G53 with a motion, G92: their axis words are no motion in the modal mode.
      if (g == 10 || g == 28 || g == 30 || g == 92 || (g > 28 && g < 29) || (g > 30 && g < 31) || (g > 92 && g < 93))
        non_modal_axes = true;
    }
    if (names_motion) return std::nullopt;
    if (axis && !non_modal_axes) return ModalArcFix{i, (mode == MotionMode::ArcCW ? "G2 " : "G3 ") + lines_after[i]};
  }
  return std::nullopt;
}

namespace {

double distance_to_segment(const geometry::Vec3& p, const geometry::Vec3& a, const geometry::Vec3& b) {
  const geometry::Vec3 ab = b - a;
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return norm(p - (a + ab * t));
}

// The 0-based source lines that move the tool, in order, before 1-based line `upto`.
std::vector<std::size_t> motion_lines_before(const ProgramTrace& trace, std::size_t upto) {
  std::vector<std::size_t> lines;
  for (const auto& s : trace.segments) {
    if (s.source_line >= upto) break;
    if (lines.empty() || lines.back() != s.source_line) lines.push_back(s.source_line);
  }
  return lines;
}

}  // namespace

ResumeChoice choose_resume_line(const ProgramTrace& trace, std::size_t last_answered,
                                const std::optional<LastSeen>& seen, std::size_t planner_lines, double tolerance) {
  planner_lines = std::max<std::size_t>(planner_lines, 1);
  if (seen && seen->answered > 0 && seen->answered <= last_answered) {
    const auto lines = motion_lines_before(trace, seen->answered);
    if (!lines.empty()) {
      const std::size_t first = lines[lines.size() - std::min(lines.size(), planner_lines)];
      for (const auto& s : trace.segments) {
        if (s.source_line < first) continue;
        if (s.source_line >= seen->answered) break;
        if (distance_to_segment(seen->work, s.work_from(), s.work_to()) <= tolerance) {
          std::ostringstream why;
          why << "the controller last reported the tool at X" << num(seen->work.x) << " Y" << num(seen->work.y)
              << " Z" << num(seen->work.z) << ", on line " << s.source_line + 1;
          return {s.source_line, why.str()};
        }
      }
    }
  }
  const auto lines = motion_lines_before(trace, last_answered);
  if (lines.empty()) return {last_answered, "no motion before the last answered line"};
  const std::size_t back = lines[lines.size() - std::min(lines.size(), planner_lines)];
  std::ostringstream why;
  why << (seen ? "the last reported position is on none of the lines the controller had queued"
               : "no position report was journaled")
      << "; backing off " << std::min(lines.size(), planner_lines)
      << " motion lines from the last answered one (the planner may have held them unmade)";
  return {back, why.str()};
}

}  // namespace cncstream::gcode
