#pragma once
// LinuxCNC's stand-alone G-code interpreter (`rs274 -g IN OUT`, Debian
// package linuxcnc-uspace) as a second opinion on our programs: it must
// accept them, and the moves it makes of them (its canonical ARC_FEED /
// STRAIGHT_FEED calls) must be the ones our interpreter makes.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cncstream/gcode/interpreter.hpp"
#include "cncstream/gcode/line_lexer.hpp"

namespace cncstream::test {

// A move as both interpreters see it: the end point, and for an arc its
// plane, centre (the in-plane coordinates; the other is zero) and turn
// (+1 counter-clockwise = G3, -1 clockwise = G2, seen as the plane's G2/G3 see it).
struct CanonMove {
  bool rapid = false;
  bool arc = false;
  gcode::Plane plane = gcode::Plane::XY;
  geometry::Vec3 to, centre;
  int turn = 0;
};

inline bool rs274_available() { return std::system("command -v rs274 >/dev/null 2>&1") == 0; }

struct Rs274Run {
  int status = -1;      // rs274's exit status (0: the whole program ran)
  std::string output;   // what it printed (errors name the line)
  std::vector<CanonMove> moves;
};

namespace detail {
inline std::vector<double> canon_args(const std::string& line, const std::string& call) {
  std::vector<double> v;
  const auto at = line.find(call + "(");
  if (at == std::string::npos) return v;
  std::string args = line.substr(at + call.size() + 1);
  args = args.substr(0, args.find(')'));
  std::stringstream ss(args);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::stod(item));
  return v;
}
}  // namespace detail

// Runs rs274 on the program text (written to a temporary file).
inline Rs274Run run_rs274(const std::string& program) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string base = (dir / ("cncstream_rs274_" + std::to_string(::getpid()))).string();
  const std::string in = base + ".ngc", out = base + ".canon", log = base + ".log";
  std::ofstream(in) << program;
  Rs274Run r;
  const std::string cmd = "rs274 -g '" + in + "' '" + out + "' >'" + log + "' 2>&1 </dev/null";
  const int raw = std::system(cmd.c_str());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  {
    std::ifstream l(log);
    std::stringstream ss;
    ss << l.rdbuf();
    r.output = ss.str();
  }
  std::ifstream canon(out);
  std::string line;
  gcode::Plane plane = gcode::Plane::XY;
  while (std::getline(canon, line)) {
    if (line.find("SELECT_PLANE(CANON_PLANE_XY)") != std::string::npos) plane = gcode::Plane::XY;
    if (line.find("SELECT_PLANE(CANON_PLANE_XZ)") != std::string::npos) plane = gcode::Plane::ZX;
    if (line.find("SELECT_PLANE(CANON_PLANE_YZ)") != std::string::npos) plane = gcode::Plane::YZ;
    for (const char* call : {"STRAIGHT_FEED", "STRAIGHT_TRAVERSE"}) {
      const auto v = detail::canon_args(line, call);
      if (v.size() >= 3) r.moves.push_back({std::string(call) == "STRAIGHT_TRAVERSE", false, plane, {v[0], v[1], v[2]}, {}, 0});
    }
    // ARC_FEED(first_end, second_end, first_centre, second_centre, rotation,
    // axis_end, ...), the plane's axes in G2/G3's order: XY, ZX, YZ.
    const auto v = detail::canon_args(line, "ARC_FEED");
    if (v.size() >= 6) {
      CanonMove m;
      m.arc = true;
      m.plane = plane;
      m.turn = v[4] > 0 ? 1 : -1;
      switch (plane) {
        case gcode::Plane::XY: m.to = {v[0], v[1], v[5]}; m.centre = {v[2], v[3], 0}; break;
        case gcode::Plane::ZX: m.to = {v[1], v[5], v[0]}; m.centre = {v[3], 0, v[2]}; break;
        case gcode::Plane::YZ: m.to = {v[5], v[0], v[1]}; m.centre = {0, v[2], v[3]}; break;
      }
      r.moves.push_back(m);
    }
  }
  std::filesystem::remove(in);
  std::filesystem::remove(out);
  std::filesystem::remove(log);
  return r;
}

// Our interpreter's moves of the same program; `error` gets the first line
// it refused (empty: none).
inline std::vector<CanonMove> our_moves(const std::string& program, std::string& error) {
  std::vector<CanonMove> moves;
  gcode::ParserState s;
  std::istringstream in(program);
  std::string line;
  while (std::getline(in, line)) {
    const gcode::CleanLine c = gcode::clean_line(line);
    if (c.text.empty()) continue;
    const gcode::BlockResult r = gcode::execute_block(s, c.text);
    if (!r.ok()) {
      if (error.empty()) error = line + " -> error " + std::to_string(r.status);
      continue;
    }
    for (const gcode::Action& a : r.actions) {
      if (const auto* lm = std::get_if<gcode::LinearMove>(&a)) moves.push_back({lm->rapid, false, gcode::Plane::XY, lm->to, {}, 0});
      if (const auto* am = std::get_if<gcode::ArcMove>(&a)) {
        CanonMove m;
        m.arc = true;
        m.plane = am->plane;
        m.to = am->to;
        m.centre = am->center;
        // Only the in-plane coordinates of the centre mean anything.
        if (am->plane == gcode::Plane::XY) m.centre.z = 0;
        if (am->plane == gcode::Plane::ZX) m.centre.y = 0;
        if (am->plane == gcode::Plane::YZ) m.centre.x = 0;
        m.turn = am->clockwise ? -1 : 1;
        moves.push_back(m);
      }
    }
    s = r.state;  // after M2 already reset as the firmware resets it
  }
  return moves;
}

}  // namespace cncstream::test
