#include "cncstream/session/simulator_port.hpp"

#include <fmt/core.h>

#include "cncsim/output_file.hpp"
#include "cncsim/number_text.hpp"
#include "cncsim/probe_targets.hpp"
#include "cncsim/removal.hpp"

#include <sstream>
#include <stdexcept>

#include "cncstream/cam/deviation.hpp"

namespace cncstream::session {

double parse_sim_speed(const std::string& text) {
  if (text == "max") return 0;
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(v > 0))
    throw std::invalid_argument("--sim-speed '" + text + "': expected 'max' or a positive time scale (1 = real time)");
  return v;
}

cncsim::StickOuts parse_sim_stick_outs(const std::string& tool_table) { return cncsim::parse_tool_stick_outs(tool_table); }

void check_sim_tool_sensor(const std::string& text) { cncsim::parse_tool_sensor(text); }

cncsim::ToolTable parse_sim_tool_shapes(const std::string& tool_table) { return cncsim::parse_tool_table(tool_table); }

geometry::Box3 parse_sim_stock(const std::string& text) {
  const cncsim::StockBox b = cncsim::parse_stock_box(text, 1.0);
  return geometry::Box3{b.lo, b.hi};
}

geometry::Vec3 parse_sim_position(const std::string& text) {
  const auto p = cncsim::vec3_from(text);
  if (!p) throw std::invalid_argument("'" + text + "': expected X,Y,Z (machine mm)");
  return *p;
}

void check_sim_corner_plate(const std::string& text) { cncsim::parse_corner_plate(text, 0, 0, 0); }

SimulatorPort::SimulatorPort(SimulatorOptions options) : opt_(std::move(options)) {
  cncsim::MachineOptions mo;
  if (!opt_.settings_file.empty()) mo.store_path = opt_.settings_file;
  mo.strict = opt_.strict;
  mo.firmware = opt_.firmware;
  mo.faults = opt_.faults;
  mo.probe_surface_z = opt_.probe_surface_z;
  mo.start_position = opt_.start_position;
  mo.stick_outs = opt_.stick_outs;
  if (!mo.stick_outs.empty()) {
    mo.start_tool = mo.stick_outs.begin()->first;
    mo.operator_mounts_tools = true;
  }
  if (!opt_.tool_sensor.empty()) mo.probe_faces.push_back(cncsim::parse_tool_sensor(opt_.tool_sensor));
  mo.link_bytes_per_second = cncsim::link_bytes_per_second_for_baud(opt_.baud);
  cncsim::PtyOptions po;
  po.speed = parse_sim_speed(opt_.speed);
  po.link = opt_.link;
  mo.instant_waits = po.speed <= 0;
  std::optional<cncsim::StockBox> stock_box;
  if (opt_.design) {
    stock_box = cncsim::stock_box_for(*opt_.design, opt_.resolution);
    if (opt_.stock) {
      stock_box->lo = opt_.stock->lo;
      stock_box->hi = opt_.stock->hi;
    }
  } else if (opt_.stock) {
    stock_box = cncsim::StockBox{opt_.stock->lo, opt_.stock->hi, opt_.resolution};
  }
  // What touches the plate, the sensor or a corner plate's wall is the mounted tool's cutter.
  if (opt_.tools) mo.tool_shapes = *opt_.tools;
  else if (opt_.cutter) mo.tool_shapes[mo.start_tool] = *opt_.cutter;
  if (!opt_.corner_plate.empty()) {
    if (!stock_box) throw std::invalid_argument("the simulator's corner plate sits on the stock's corner: give a stock");
    mo.probe_faces.push_back(
        cncsim::parse_corner_plate(opt_.corner_plate, stock_box->lo.x, stock_box->lo.y, stock_box->hi.z));
  }
  if (!opt_.touch_plate.empty()) {
    if (!stock_box) throw std::invalid_argument("the simulator's touch plate lies on the stock: an STL job or --sim-design");
    mo.probe_faces.push_back(cncsim::parse_touch_plate(opt_.touch_plate, stock_box->hi.z));
  }
  machine_ = std::make_unique<cncsim::Machine>(mo);
  if (opt_.design) {
    if (!opt_.cutter) throw std::invalid_argument("sim verify needs the cutter (--tool)");
    // Grid nodes exactly on a vertical wall of the design have no single
    // design height: shift the grid off the part's round coordinates.
    cncsim::StockBox box = cncsim::stock_box_for(*opt_.design, opt_.resolution);
    if (opt_.stock) {
      box.lo = opt_.stock->lo;
      box.hi = opt_.stock->hi;
    }
    box.lo.x += 0.373 * opt_.resolution;
    box.lo.y += 0.411 * opt_.resolution;
    removal_ = std::make_unique<cncsim::MaterialRemoval>(box, *opt_.cutter);
    if (opt_.tools) removal_->set_tool_table(*opt_.tools);
    removal_->attach(*machine_);
    // The tool in the spindle at the start cuts until the operator mounts another.
    if (!mo.stick_outs.empty()) machine_->request_mount(mo.start_tool);
  }
  front_ = std::make_unique<cncsim::PtyFrontEnd>(*machine_, po);
  path_ = opt_.link ? opt_.link->string() : front_->slave_path();
}

void SimulatorPort::start() {
  if (thread_.joinable() || finished_) return;
  thread_ = std::thread([this] {
    try {
      vanished_ = front_->run(stop_) == cncsim::PtyFrontEnd::Exit::Vanished;
    } catch (const cncsim::RxOverflowError& e) {
      fatal_ = std::string("RX buffer overflow (strict): ") + e.what();
    } catch (const std::exception& e) {
      fatal_ = e.what();
    }
    // Whatever ended the loop, the host must see the port go away.
    front_.reset();
    ended_ = true;
  });
}

SimulatorPort::~SimulatorPort() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

SimulatorPort::Report SimulatorPort::finish(bool let_motion_finish) {
  Report r;
  if (finished_) return r;
  finished_ = true;
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (let_motion_finish && fatal_.empty()) machine_->run_until_idle();
  std::ostringstream o;
  o << "sim: " << machine_->lines_received() << " lines received, " << machine_->lines_answered() << " answered, "
    << machine_->lines_executed() << " executed, " << machine_->rx_bytes_dropped() << " RX bytes dropped";
  if (vanished_) o << "; vanished (fault injection)";
  o << "\n";
  o << "sim: " << cncsim::link_summary(machine_->link_stats(), opt_.baud, cncsim::MachineOptions{}.starved_below_blocks)
    << "\n";
  const auto mpos = machine_->machine_position();
  const auto wpos = machine_->work_position();
  o << fmt::format("sim: final position MPos {:.3f},{:.3f},{:.3f} WPos {:.3f},{:.3f},{:.3f}, state ", mpos.x, mpos.y,
                   mpos.z, wpos.x, wpos.y, wpos.z)
    << machine_->state_name() << "\n";
  if (!fatal_.empty()) {
    o << "sim: stopped early: " << fatal_ << "\n";
    r.overflowed = fatal_.find("overflow") != std::string::npos;
  }
  if (machine_->rx_bytes_dropped() > 0) r.overflowed = true;
  if (removal_) {
    o << "sim: " << removal_->stock().removed_volume() << " mm^3 removed in " << removal_->segments()
      << " cutting segments\n";
    for (int t : removal_->unknown_tools())
      o << "sim: warning: the program selected T" << t << ", which the tool table does not hold; the cutter was kept\n";
    if (!opt_.result.empty()) {
      // In the job's work coordinates, with where its work zero sat on the
      // machine, so a later setup (its zero elsewhere) places it.
      const auto stl = removal_->write_result(opt_.result, opt_.work_offset, cncsim::start_tool_work_origin(*machine_));
      o << "sim: machined surface written to " << opt_.result << " (+ .txt) and " << stl.string() << "\n";
    }
    const auto heights = cam::design_heights(*opt_.design, removal_->stock().grid());
    const auto result = cam::compare_to_design(removal_->stock(), heights, opt_.tolerance);
    o << "verify (" << removal_->cutter().description() << ", grid " << opt_.resolution << " mm):\n"
      << result.stats.summary() << "\n";
    r.gouged = result.stats.gouged > 0;
    if (result.stats.has_gouge) r.largest_gouge_mm = -result.stats.largest_gouge.value;
    if (!opt_.png.empty()) {
      cncsim::write_whole(opt_.png, [&](const std::filesystem::path& file) {
        cam::write_deviation_png(file, result, "cncstream sim verify", removal_->cutter().description());
      });
      o << "verify: deviation map written to " << opt_.png << "\n";
    }
  }
  r.text = o.str();
  return r;
}

}  // namespace cncstream::session
