#pragma once
// cncstreamd's configuration: a TOML file (docs/api-v1.md, "Configuration")
// and command-line overrides. Every field has a default, so no file at all
// gives one simulated machine listening on 127.0.0.1:8420.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/daemon/tool_change_settings.hpp"

namespace cncstream::daemon {

struct MachineConfig {
  std::string name = "sim";
  std::string port = "sim";  // a device path, /dev/serial/by-id/..., "auto" or "sim"
  unsigned baud = 115200;
  std::string profile;       // "": identify
  double reconnect_s = 1.0;  // reopen a vanished port this often
  // port = "sim" only.
  std::string sim_speed = "max";
  bool sim_verify = true;            // STL jobs: cut a fresh stock and verify it against the part
  std::size_t sim_vanish_after = 0;  // fault for tests: the first simulator vanishes after N answers
  std::string sim_settings;          // persistent simulator settings file ("" : defaults)
  std::string sim_firmware = "grbl";  // grbl or grblhal (its $341 and Tool state: docs/tool-change.md)
  double sim_resolution = 0.1;       // stock grid step of the verify, mm
  double sim_tolerance = 0.05;       // verify tolerance, mm
  // The simulated machine's tools and probes (docs/tool-change.md): stick-outs
  // ("1=flat:6@30,2=ball:3.175@37.3"; the simulated operator mounts a tool when
  // the operator confirms the mount), a tool-length sensor "X,Y,Z" (machine
  // coordinates, its top) and a plane every probe touches (machine Z).
  std::string sim_tool_table;
  std::string sim_tool_sensor;
  std::optional<double> sim_probe_surface_z;
  // A stock block ("X0,Y0,Z0:X1,Y1,Z1", machine mm) with a corner plate
  // ("THICKNESS,LIP[,SIZE]") on its X-min/Y-min corner, and where the tool
  // is at power-on ("X,Y,Z", machine mm): corner probing on the simulator.
  std::string sim_stock;
  std::string sim_corner_plate;
  std::string sim_start;
  // [machine.tool_change]: the routine a program's tool change runs.
  ToolChangeSettings tool_change;
  // In a shop ([shop] url): tags a shop job's needs must be among, and
  // whether the machine takes jobs from the shop's queue when it is free.
  std::vector<std::string> capabilities;
  bool shop_claim = true;
};

// Joining a shop (docs/shop.md): "" url leaves the daemon on its own.
struct ShopSection {
  std::string url;            // postgresql://PC_ROLE@HUB/DB
  std::string name = "shop";  // the shop's name (MQTT topics)
  std::string pc;             // this PC's name ("" : the host name)
  double lease_s = 30;        // a shop job's lease, renewed by heartbeats
  double heartbeat_s = 5;
  // The shop view's pushes: a re-read of the hub at most this often (not in
  // the TOML: the benchmark's knob, tools/bench_shop_latency.cpp).
  double watch_min_interval_s = 0.2;
  // MTConnect SHDR adapters: machine i listens on mtconnect_port + i (0: any
  // free port, tests); none without it.
  std::optional<unsigned short> mtconnect_port;
  std::string mtconnect_address = "127.0.0.1";
  // MQTT (Mosquitto): none without mqtt_host.
  std::string mqtt_host;
  unsigned short mqtt_port = 1883;
  std::string mqtt_username, mqtt_password, mqtt_ca_file;
  double mqtt_keepalive_s = 10;
};

// A WHB04B pendant driving one machine ([[pendant]] in the file). The daemon
// opens the USB receiver (and keeps looking while none is plugged in).
struct PendantSection {
  std::string machine;                // the machine it drives (must be configured)
  double lease_s = 0.2;               // a continuous jog ends this long after the last wheel report
  std::vector<std::string> macros;    // "N=ACTION" (docs/pendant.md)
};

struct Limits {
  std::uint64_t max_upload_bytes = 200'000'000;
  std::size_t max_json_bytes = 1 << 20;
  std::size_t max_connections = 128;
  std::size_t max_ws_clients = 64;
  double header_timeout_s = 10;
  double body_timeout_s = 120;
  std::size_t ws_queue_messages = 1024;
  double max_grid_nodes = 50e6;
  double control_idle_s = 300;
  unsigned worker_threads = 0;  // 0: hardware concurrency
};

struct SecurityConfig {
  bool require_token = false;  // forced on for a non-loopback listen address
  std::vector<std::string> allowed_origins;
  std::vector<std::string> allowed_hosts;
};

struct DaemonConfig {
  std::string listen_address = "127.0.0.1";
  unsigned short listen_port = 8420;  // 0: any free port (tests)
  std::filesystem::path data_dir;     // "" : default_data_dir()
  std::filesystem::path journal;      // "" : <data_dir>/journal.sqlite, or the CLI's journal without a data_dir
  std::filesystem::path web_root;     // "" : found at start (share/cncstream/web, then the source tree's web/)
  std::vector<MachineConfig> machines{MachineConfig{}};
  std::vector<PendantSection> pendants;
  Limits limits;
  SecurityConfig security;
  ShopSection shop;

  bool listen_is_loopback() const;
  bool token_required() const { return security.require_token || !listen_is_loopback(); }
};

// $XDG_STATE_HOME/cncstream/daemon, else ~/.local/state/cncstream/daemon.
std::filesystem::path default_data_dir();

// The journal the daemon uses: `journal` when set; else, when `data_dir` is
// set, <data_dir>/journal.sqlite (a daemon given its own folder keeps its
// history there too); else the CLI's (transport::Journal::default_path()),
// so `cncstream jobs` lists the default daemon's jobs.
std::filesystem::path journal_path(const DaemonConfig& c);

// Throws std::invalid_argument naming the file, line and key of a bad value.
DaemonConfig load_config(const std::filesystem::path& file);
DaemonConfig parse_config(std::string_view toml_text, const std::string& source_name);

// "ADDR:PORT", "[::1]:PORT"; throws std::invalid_argument naming the text.
void apply_listen(DaemonConfig& c, const std::string& addr_port);
// "NAME=PORT[,profile=P,baud=B,sim_speed=S,reconnect_s=R]"; throws naming the text.
MachineConfig parse_machine_option(const std::string& text);

// Checks names are unique and well-formed ([A-Za-z0-9_-]{1,32}) and values in range.
void validate(const DaemonConfig& c);

}  // namespace cncstream::daemon
