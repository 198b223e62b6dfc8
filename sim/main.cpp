// cncsim: a GRBL 1.1h router on a pseudo-terminal.
//   cncsim [--link PATH] [--speed K|max] [--baud B] [--settings FILE] [--strict] [faults] [stock]
//          (with --design: verify the cut at exit; --result writes it as .f32 and .stl;
//          --stock-from RESULT.f32 --position X,Y,Z start from a saved state)
//   cncsim verify --design part.stl --result RESULT.f32 [--tolerance T] [--png MAP.png]
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <atomic>
#include <cctype>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "cncsim/machine.hpp"
#include "cncsim/number_text.hpp"
#include "cncsim/output_file.hpp"
#include "cncsim/pty_frontend.hpp"
#include "cncsim/removal.hpp"
#include "cncstream/cam/deviation.hpp"
#include "cncstream/cam/height_field_io.hpp"
#include "cncstream/geometry/stl.hpp"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

// "LINE:OFFSET", "LINE:eol" or "LINE:X" (its first X) for the wire faults at a point.
void parse_byte_faults(const std::vector<std::string>& specs, const char* flag,
                       std::map<std::size_t, cncsim::ByteOfLine>& out) {
  for (const std::string& s : specs) {
    const auto colon = s.find(':');
    const auto line = colon == std::string::npos ? std::nullopt : cncsim::number_from<std::size_t>(s.substr(0, colon));
    const std::string word = colon == std::string::npos ? std::string() : s.substr(colon + 1);
    const auto offset = cncsim::number_from<std::size_t>(word);
    if (line && *line > 0 && offset) {
      out[*line] = cncsim::ByteOfLine::at(*offset);
    } else if (line && *line > 0 && word == "eol") {
      out[*line] = cncsim::ByteOfLine::end_of_line();
    } else if (line && *line > 0 && word.size() == 1 && std::isalpha(static_cast<unsigned char>(word[0]))) {
      out[*line] = cncsim::ByteOfLine::first(static_cast<char>(std::toupper(static_cast<unsigned char>(word[0]))));
    } else {
      throw std::invalid_argument(std::string(flag) + " '" + s +
                                  "': expected LINE:OFFSET (0-based byte of that line), LINE:eol or LINE:LETTER, "
                                  "LINE >= 1");
    }
  }
}

cncstream::geometry::Vec3 parse_position(const std::string& text) {
  const auto p = cncsim::vec3_from(text);
  if (!p) throw std::invalid_argument("--position '" + text + "': expected X,Y,Z (mm, machine coordinates)");
  return *p;
}

// How often each N word ran: a program numbered N1..Nk streamed once and
// in full runs each exactly once.
struct NumberedTally {
  std::vector<std::uint32_t> times;  // times[N]
  void add(long n) {
    if (n <= 0) return;
    if (static_cast<std::size_t>(n) >= times.size()) times.resize(static_cast<std::size_t>(n) + 1, 0);
    ++times[static_cast<std::size_t>(n)];
  }
  std::string summary() const {
    std::size_t distinct = 0, again = 0, missing = 0;
    for (std::size_t n = 1; n < times.size(); ++n) {
      if (times[n] == 0) ++missing;
      else ++distinct;
      if (times[n] > 1) ++again;
    }
    if (distinct == 0) return "";
    return "numbered lines: " + std::to_string(distinct) + " of N1..N" + std::to_string(times.size() - 1) + " ran, " +
           std::to_string(missing) + " never, " + std::to_string(again) + " more than once";
  }
};

int run_verify(const std::string& design_path, const std::string& result_path, double tolerance,
               const std::string& png) {
  auto design = cncstream::geometry::load_stl(design_path).mesh;
  const auto field = cncstream::cam::read_height_field(result_path);
  // A cut in work coordinates that says where the model sat: the design goes there.
  if (field.work_offset) design.translate(*field.work_offset);
  const auto stock = cncsim::stock_from_heights(field.grid, field.z);
  const auto heights = cncstream::cam::design_heights(design, field.grid);
  const auto result = cncstream::cam::compare_to_design(stock, heights, tolerance);
  std::cout << result.stats.summary() << "\n";
  if (!png.empty())
    cncsim::write_whole(png, [&](const std::filesystem::path& file) {
      cncstream::cam::write_deviation_png(file, result, "cncsim verify", design_path);
    });
  return result.stats.gouged == 0 ? 0 : 3;
}

int run(int argc, char** argv) {
  CLI::App app{"cncsim: a simulated GRBL 1.1h 3-axis router on a pseudo-terminal"};
  std::string link, speed_text = "1", settings_path, stock_text, design_path, tool_spec = "flat:6", result_path;
  bool strict = false;
  std::size_t drop_every = 0, corrupt_every = 0, vanish_after = 0;
  int homing_fail = 0;
  double resolution = 0.1;
  std::optional<double> probe_z;
  std::vector<std::string> error_at, alarm_at, stall_at, drop_at, corrupt_at;
  std::string stock_from, position_text;
  app.add_option("--link", link, "make PATH a symlink to the pty slave");
  app.add_option("--speed", speed_text, "time scale: K (1 = real time) or 'max'");
  double baud = 115200;
  std::size_t starved_below = 8;
  app.add_option("--baud", baud,
                 "serial link rate: bytes arrive at baud/10 per second of virtual time (scaled by --speed like the "
                 "motion), as on a USB-serial GRBL board; 0 = unthrottled")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--starved-below", starved_below,
                 "count the planner as starved below this many blocks while a line is on its way")
      ->check(CLI::Range(std::size_t{1}, cncsim::kPlannerBlocks))
      ->capture_default_str();
  app.add_option("--settings", settings_path, "settings file ($$, G10/G28.1/G30.1 data, $N lines) kept across runs");
  app.add_flag("--strict", strict, "any RX buffer overflow is fatal (exit 2)");
  app.add_option("--drop-every", drop_every, "drop every Nth byte received");
  app.add_option("--corrupt-every", corrupt_every, "flip a bit in every Nth byte received");
  app.add_option("--error-at", error_at, "LINE:E answer line LINE with error:E (repeatable)");
  app.add_option("--alarm-at", alarm_at, "LINE:A raise ALARM:A when line LINE arrives (repeatable)");
  app.add_option("--stall-at", stall_at, "LINE:S stop answering for S seconds at line LINE (repeatable)");
  app.add_option("--drop-at", drop_at,
                 "LINE:OFFSET drop that byte of line LINE; LINE:eol its end of line; LINE:X its first X (repeatable)");
  app.add_option("--corrupt-at", corrupt_at, "LINE:OFFSET|eol|LETTER flip a bit in that byte of line LINE (repeatable)");
  app.add_option("--vanish-after", vanish_after, "close the pty after N answered lines");
  app.add_option("--homing-fail", homing_fail, "make $H fail with ALARM:A (6-9)")->check(CLI::Range(6, 9));
  app.add_option("--probe-z", probe_z, "G38.x touches the plane Z (machine coordinates)");
  app.add_option("--stock", stock_text, "stock block X0,Y0,Z0:X1,Y1,Z1 in machine coordinates (material removal)");
  app.add_option("--design", design_path, "design STL: the stock is its bounding box");
  app.add_option("--resolution", resolution, "stock grid step, mm")->check(CLI::PositiveNumber);
  app.add_option("--tool", tool_spec, "cutter spec, e.g. ball:3.175, flat:6, bull:6:1");
  app.add_option("--result", result_path, "write the machined surface here on exit (.f32 + .f32.txt, and .stl)");
  app.add_option("--stock-from", stock_from, "start with this machined surface (a --result .f32 of an earlier run) as the stock");
  app.add_option("--position", position_text, "start with the tool here, X,Y,Z machine mm (where an earlier run stopped)");
  std::string tool_table_text, png_path;
  double tolerance = 0.05;
  app.add_option("--tool-table", tool_table_text,
                 "tools by T number, e.g. 1=ball:3.175,2=bull:3.175:0.79, or a file of N=SPEC lines; SPEC@L gives "
                 "the tool's stick-out L mm (1=flat:6@30,2=ball:3.175@37.3): the lowest T is in the spindle at "
                 "power-on and the tip of a longer tool sits lower by the difference");
  std::string touch_plate_text, tool_sensor_text;
  app.add_option("--touch-plate", touch_plate_text,
                 "X,Y,THICKNESS: a 40 mm touch plate centred on X,Y (machine mm) lying on the stock's top");
  app.add_option("--tool-sensor", tool_sensor_text, "X,Y,Z: a fixed tool-length sensor, its top at Z (machine mm)");
  std::string corner_plate_text;
  app.add_option("--corner-plate", corner_plate_text,
                 "THICKNESS,LIP[,SIZE]: a corner touch plate on the stock's X-min/Y-min corner, its outer walls LIP "
                 "outside the stock's edges (SIZE 50 mm); the tool's cutter touches it with its flank");
  app.add_option("--png", png_path, "with --design: write the deviation map of the verify at exit");
  app.add_option("--tolerance", tolerance, "with --design: verify tolerance, mm")->check(CLI::PositiveNumber);

  auto* verify = app.add_subcommand("verify", "compare a machined result with the design");
  std::string v_design, v_result, v_png;
  double v_tol = 0.05;
  verify->add_option("--design", v_design, "design STL")->required();
  verify->add_option("--result", v_result, "height field written by --result")->required();
  verify->add_option("--tolerance", v_tol, "mm")->check(CLI::PositiveNumber);
  verify->add_option("--png", v_png, "write a deviation map");
  std::string firmware_text = "grbl";
  app.add_option("--firmware", firmware_text,
                 "grbl (GRBL 1.1h) or grblhal (its banner, $I, 1024-byte RX buffer, $341 and the Tool state at M6)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    if (*verify) return run_verify(v_design, v_result, v_tol, v_png);

    cncsim::MachineOptions options;
    if (!settings_path.empty()) options.store_path = settings_path;
    options.strict = strict;
    options.firmware = cncsim::parse_firmware(firmware_text);
    options.link_bytes_per_second = cncsim::link_bytes_per_second_for_baud(baud);
    options.starved_below_blocks = starved_below;
    options.faults.drop_every = drop_every;
    options.faults.corrupt_every = corrupt_every;
    options.faults.vanish_after = vanish_after;
    options.faults.homing_failure = homing_fail;
    options.probe_surface_z = probe_z;
    cncsim::parse_line_faults(error_at, "--error-at", options.faults.error_at);
    cncsim::parse_line_faults(alarm_at, "--alarm-at", options.faults.alarm_at);
    cncsim::parse_line_faults(stall_at, "--stall-at", options.faults.stall_at);
    parse_byte_faults(drop_at, "--drop-at", options.faults.drop_byte_at);
    parse_byte_faults(corrupt_at, "--corrupt-at", options.faults.corrupt_byte_at);
    if (!position_text.empty()) options.start_position = parse_position(position_text);
    cncsim::PtyOptions pty;
    if (!link.empty()) pty.link = link;
    if (speed_text == "max") {
      pty.speed = 0;
      options.instant_waits = true;
    } else {
      std::size_t used = 0;
      pty.speed = std::stod(speed_text, &used);
      if (used != speed_text.size() || !(pty.speed > 0))
        throw std::invalid_argument("--speed '" + speed_text + "': expected a positive number or 'max'");
    }

    std::unique_ptr<cncsim::MaterialRemoval> removal;
    std::optional<cncstream::geometry::Mesh> design;
    if (!design_path.empty()) design = cncstream::geometry::load_stl(design_path).mesh;
    if (!stock_from.empty()) {
      // A saved state: the surface an earlier run left is the stock.
      if (!stock_text.empty()) throw std::invalid_argument("--stock-from and --stock: give one");
      auto field = cncstream::cam::read_height_field(stock_from);
      if (field.work_origin) {
        // Saved in work coordinates with its work zero's machine position: back to machine coordinates.
        field.grid.x0 += field.work_origin->x;
        field.grid.y0 += field.work_origin->y;
        for (float& z : field.z) z = static_cast<float>(static_cast<double>(z) + field.work_origin->z);
      }
      removal = std::make_unique<cncsim::MaterialRemoval>(cncsim::stock_from_heights(field.grid, field.z),
                                                          cncstream::cam::parse_cutter_spec(tool_spec));
      if (!tool_table_text.empty()) removal->set_tool_table(cncsim::parse_tool_table(tool_table_text));
      if (!options.probe_surface_z) options.probe_surface_z = removal->stock().top();
    } else if (!stock_text.empty() || design) {
      const cncstream::cam::Cutter cutter = cncstream::cam::parse_cutter_spec(tool_spec);
      const cncsim::StockBox box = !stock_text.empty() ? cncsim::parse_stock_box(stock_text, resolution)
                                                       : cncsim::stock_box_for(*design, resolution);
      removal = std::make_unique<cncsim::MaterialRemoval>(box, cutter);
      if (!tool_table_text.empty()) removal->set_tool_table(cncsim::parse_tool_table(tool_table_text));
      // A probe (G38.x) without --probe-z touches the stock's top.
      if (!options.probe_surface_z) options.probe_surface_z = box.hi.z;
    } else if (!result_path.empty() || !tool_table_text.empty() || !png_path.empty()) {
      throw std::invalid_argument("--result, --tool-table and --png need a stock (--stock or --design)");
    }
    if (!tool_table_text.empty()) {
      options.stick_outs = cncsim::parse_tool_stick_outs(tool_table_text);
      if (!options.stick_outs.empty()) options.start_tool = options.stick_outs.begin()->first;
    }
    if (!touch_plate_text.empty()) {
      if (!removal) throw std::invalid_argument("--touch-plate lies on the stock: give --stock or --design");
      options.probe_faces.push_back(cncsim::parse_touch_plate(touch_plate_text, removal->stock().top()));
    }
    if (!tool_sensor_text.empty()) options.probe_faces.push_back(cncsim::parse_tool_sensor(tool_sensor_text));
    if (removal) {
      // The probe input sees the mounted tool's cutter (a side probe meets its flank).
      if (!tool_table_text.empty()) options.tool_shapes = cncsim::parse_tool_table(tool_table_text);
      else options.tool_shapes[options.start_tool] = removal->cutter();
    }
    if (!corner_plate_text.empty()) {
      if (!removal) throw std::invalid_argument("--corner-plate sits on the stock's corner: give --stock or --design");
      const auto& grid = removal->stock().grid();
      options.probe_faces.push_back(
          cncsim::parse_corner_plate(corner_plate_text, grid.x0, grid.y0, removal->stock().top()));
    }
    // With a plate or a sensor the probe touches those, not the stock's top everywhere.
    if (!options.probe_faces.empty() && !probe_z) options.probe_surface_z.reset();
    cncsim::Machine machine(options);
    if (removal) removal->attach(machine);
    NumberedTally tally;
    machine.set_line_observer([&tally](const cncsim::ExecutedLine& l) { tally.add(l.n); });

    if (std::signal(SIGINT, on_signal) == SIG_ERR || std::signal(SIGTERM, on_signal) == SIG_ERR)
      throw std::runtime_error("cannot install the SIGINT/SIGTERM handlers");
    cncsim::PtyFrontEnd front(machine, pty);
    std::cout << front.slave_path() << std::endl;

    int code = 0;
    try {
      if (front.run(g_stop) == cncsim::PtyFrontEnd::Exit::Vanished)
        std::cerr << "cncsim: vanished after " << machine.lines_answered() << " answered lines (--vanish-after)\n";
    } catch (const cncsim::RxOverflowError& e) {
      std::cerr << "cncsim: fatal (--strict): " << e.what() << "\n";
      code = 2;
    }
    // Serving has ended (Ctrl-C, SIGTERM, the port vanished): another signal
    // during the end-of-run work (result, verify) ends the program at once;
    // its files are written whole or not at all.
    // SIG_DFL for signals this program may catch cannot fail.
    (void)std::signal(SIGINT, SIG_DFL);
    (void)std::signal(SIGTERM, SIG_DFL);
    if (removal && (!result_path.empty() || design))
      std::cerr << "cncsim: writing the result and verifying (Ctrl-C again to quit without them)\n";
    std::cerr << "cncsim: " << machine.lines_received() << " lines received, " << machine.lines_answered()
              << " answered, " << machine.lines_executed() << " executed, " << machine.rx_bytes_dropped()
              << " RX bytes dropped";
    if (removal) std::cerr << ", " << removal->stock().removed_volume() << " mm^3 removed";
    std::cerr << "\n";
    if (const auto numbered = tally.summary(); !numbered.empty()) std::cerr << "cncsim: " << numbered << "\n";
    std::cerr << "cncsim: " << cncsim::link_summary(machine.link_stats(), baud, starved_below) << "\n";
    {
      const auto m = machine.machine_position();
      std::cerr << fmt::format("cncsim: final position MPos {:.4f},{:.4f},{:.4f}, state {}\n", m.x, m.y, m.z,
                               machine.state_name());
    }
    if (removal) {
      for (int t : removal->unknown_tools())
        std::cerr << "cncsim: warning: T" << t << " is not in the tool table; the cutter was kept\n";
      if (!result_path.empty()) {
        const auto stl = removal->write_result(result_path, std::nullopt, cncsim::start_tool_work_origin(machine));
        std::cerr << "cncsim: machined surface written to " << result_path << " and " << stl.string() << "\n";
      }
    }
    if (removal && design) {
      // The end-of-run verify: the machined stock against the design.
      const auto heights = cncstream::cam::design_heights(*design, removal->stock().grid());
      const auto result = cncstream::cam::compare_to_design(removal->stock(), heights, tolerance);
      std::cerr << "cncsim verify against " << design_path << ":\n" << result.stats.summary() << std::endl;
      if (!png_path.empty()) {
        cncsim::write_whole(png_path, [&](const std::filesystem::path& file) {
          cncstream::cam::write_deviation_png(file, result, "cncsim verify", design_path);
        });
        std::cerr << "cncsim: deviation map written to " << png_path << "\n";
      }
      if (code == 0 && result.stats.gouged > 0) code = 3;
    }
    return code;
  } catch (const std::exception& e) {
    std::cerr << "cncsim: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes run() (setting up the options, or an exception that is not
  // an std::exception) ends the program with a message, not std::terminate.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "cncsim: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "cncsim: error: an unknown exception\n";
  }
  return 1;
}
