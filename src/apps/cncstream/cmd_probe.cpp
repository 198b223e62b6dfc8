// `cncstream probe corner|xy|z PORT`: set work zero with a corner touch
// plate (protocol/corner_probe.hpp), and `cncstream outline FILE PORT`: trace
// a program's XY hull (or box) at a safe height before cutting
// (protocol/outline_trace.hpp). Each runs on one machine session
// (routine_session.hpp); the result is shown and confirmed before it is
// written (--yes confirms it).
#include <fmt/core.h>

#include <iostream>
#include <memory>

#include "cncsim/probe_targets.hpp"
#include "cncstream/cam/cutter.hpp"
#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/protocol/corner_probe.hpp"
#include "cncstream/protocol/line_cleaner.hpp"
#include "cncstream/protocol/outline_trace.hpp"
#include "cncstream/session/simulator_port.hpp"
#include "commands.hpp"
#include "routine_session.hpp"

namespace cncstream::app {

namespace detail_cmd_probe {

struct ProbeCliOptions {
  ConnectionOptions conn;
  SimCliOptions sim;
  std::string mode;
  std::string plate = "5,3";  // THICKNESS,LIP[,SIZE]
  std::string tool = "flat:6";
  protocol::CornerProbeConfig cfg;
  std::string sim_stock = "20,20,-50:120,100,-30";
  std::string sim_start;
};

protocol::CornerPlate parse_plate(const std::string& text) {
  // The simulator's parser knows the form; the plate's place does not matter here.
  const cncsim::ProbeFace f = cncsim::parse_corner_plate(text, 0, 0, 0);
  protocol::CornerPlate p;
  p.thickness = f.top;
  p.lip = -f.x0;
  p.size = f.x1 - f.x0;
  return p;
}

int run_probe(ProbeCliOptions o) {
  o.cfg.axes = protocol::parse_corner_axes(o.mode);
  try {
    o.cfg.plate = parse_plate(o.plate);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument("--plate '" + o.plate +
                                "': expected THICKNESS,LIP[,SIZE] (mm: thickness > 0, lip >= 0, size > lip)");
  }
  const cam::Cutter cutter = cam::parse_cutter_spec(o.tool);
  o.cfg.tool_radius = cutter.radius;
  auto routine = std::make_shared<protocol::CornerProbeRoutine>(o.cfg);
  session::SimulatorOptions so = simulator_options(o.sim);
  if (o.conn.port == "sim") {
    // A block with the plate on its X-min/Y-min corner, the bit over the plate.
    const geometry::Box3 box = session::parse_sim_stock(o.sim_stock);
    so.stock = box;
    so.cutter = cutter;
    so.corner_plate = o.plate;
    if (!o.sim_start.empty()) {
      try {
        so.start_position = session::parse_sim_position(o.sim_start);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("--sim-start ") + e.what());
      }
    } else {
      const auto& pl = o.cfg.plate;
      so.start_position = geometry::Vec3{box.lo.x - pl.lip + pl.size / 2, box.lo.y - pl.lip + pl.size / 2,
                               box.hi.z + pl.thickness + 10};
    }
  }
  std::cerr << fmt::format("corner probe ({}): plate {} mm thick, lip {} mm, {} mm; {} (radius {} mm)\n",
                           protocol::to_string(o.cfg.axes), o.cfg.plate.thickness, o.cfg.plate.lip, o.cfg.plate.size,
                           cutter.description(), cutter.radius);
  const int code = run_machine_routine(o.conn, so, routine);
  const auto& r = routine->result();
  if (r.edge_x && r.edge_y)
    std::cout << fmt::format("stock corner: machine X{:.3f} Y{:.3f}\n", *r.edge_x, *r.edge_y);
  if (r.top_z) std::cout << fmt::format("stock top: machine Z{:.3f}\n", *r.top_z);
  return code;
}

struct OutlineCliOptions {
  ConnectionOptions conn;
  SimCliOptions sim;
  std::string file;
  double feed = 1000;
  std::optional<double> safe_z;
  std::string shape = "hull";
};

int run_outline(const OutlineCliOptions& o) {
  const auto lines = protocol::read_gcode_lines(o.file);
  const auto cfg =
      protocol::outline_from_extent(gcode::program_extent(lines), o.safe_z, o.feed, o.file,
                                    o.shape == "box" ? protocol::OutlineShape::Box : protocol::OutlineShape::Hull);
  std::cerr << fmt::format(
      "outline of {}: the {} within X{:.3f}..{:.3f} Y{:.3f}..{:.3f} at work Z{:.3f}, F{:.0f}\n", o.file,
      cfg.shape == protocol::OutlineShape::Hull ? fmt::format("hull of its moves ({} corners)", cfg.path.size())
                                                : std::string("bounding box"),
      cfg.x0, cfg.x1, cfg.y0, cfg.y1, cfg.safe_z, cfg.feed);
  return run_machine_routine(o.conn, simulator_options(o.sim), std::make_shared<protocol::OutlineTraceRoutine>(cfg));
}

}  // namespace detail_cmd_probe

void register_probe(CLI::App& app, CommandRegistry& registry) {
  using detail_cmd_probe::ProbeCliOptions;
  auto o = std::make_shared<ProbeCliOptions>();
  auto* sub = app.add_subcommand(
      "probe",
      "Set work zero with a corner touch plate: corner (Z, then X, then Y), xy or z; put the bit over the plate's top "
      "first. The result is shown before it is written to the active work offset");
  sub->add_option("mode", o->mode, "corner (xyz), xy or z")->required();
  sub->add_option("port", o->conn.port, "Serial port, 'auto' (the one known controller board) or 'sim'")->required();
  add_link_options(sub, o->conn);
  add_sim_machine_options(sub, o->sim);
  sub->add_flag("-y,--yes", o->conn.yes, "Write the result without asking");
  sub->add_option("--timeout", o->conn.timeout_s, "Give up after this many seconds (0: never)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--plate", o->plate,
                  "THICKNESS,LIP[,SIZE]: the plate's thickness above the stock, how far its outer walls stand outside "
                  "the stock's edges, and its top's size (50 mm), mm")
      ->capture_default_str();
  sub->add_option("--tool", o->tool, "The cutter in the spindle (its radius is compensated), e.g. flat:6, ball:1/8in")
      ->capture_default_str();
  sub->add_option("--z-travel", o->cfg.z_travel, "Longest search down to the plate's top, mm")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--fast-feed", o->cfg.fast_feed, "First probe's feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--slow-feed", o->cfg.slow_feed, "Second probe's feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--clearance", o->cfg.clearance, "Travel height above the plate and distance beside it, mm")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--side-depth", o->cfg.side_depth, "How far below the plate's top the walls are probed, mm")
      ->check(CLI::PositiveNumber)->capture_default_str();
  const char* g = "Simulator (PORT=sim)";
  sub->add_option("--sim-stock", o->sim_stock, "The block, X0,Y0,Z0:X1,Y1,Z1 machine mm (the plate on its X/Y-min corner)")
      ->group(g)->capture_default_str();
  sub->add_option("--sim-start", o->sim_start, "Where the bit starts, X,Y,Z machine mm (default: 10 mm over the plate)")
      ->group(g);
  registry.add(sub, [o] { return detail_cmd_probe::run_probe(*o); });
}

void register_outline(CLI::App& app, CommandRegistry& registry) {
  using detail_cmd_probe::OutlineCliOptions;
  auto o = std::make_shared<OutlineCliOptions>();
  auto* sub = app.add_subcommand(
      "outline",
      "Trace a program's XY extent (the hull of its moves, or its bounding box) at a safe height before cutting, to "
      "see that the stock is where the program expects it and the clamps are clear of it");
  sub->add_option("file", o->file, "G-code program")->required()->check(CLI::ExistingFile);
  sub->add_option("port", o->conn.port, "Serial port, 'auto' (the one known controller board) or 'sim'")->required();
  add_link_options(sub, o->conn);
  add_sim_machine_options(sub, o->sim);
  sub->add_option("--feed", o->feed, "Trace feed, mm/min")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--safe-z", o->safe_z, "Work Z of the trace (default and lowest: the program's highest Z)");
  sub->add_option("--shape", o->shape,
                  "hull: the convex hull of the program's XY moves (within 0.1 mm); box: their bounding box")
      ->check(CLI::IsMember({"hull", "box"}))
      ->capture_default_str();
  sub->add_option("--timeout", o->conn.timeout_s, "Give up after this many seconds (0: never)")
      ->check(CLI::NonNegativeNumber);
  registry.add(sub, [o] { return detail_cmd_probe::run_outline(*o); });
}

}  // namespace cncstream::app
