#include "cncstream/daemon/config.hpp"

#define TOML_HEADER_ONLY 1
#define TOML_EXCEPTIONS 1
#include <toml++/toml.h>

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "cncstream/daemon/http_types.hpp"
#include "cncstream/protocol/toml_guard.hpp"
#include "cncstream/transport/journal.hpp"

namespace cncstream::daemon {

namespace {

std::string where(const std::string& source, const toml::node& n) {
  const auto& s = n.source();
  std::string w = source;
  if (s.begin.line) {
    w += ":";
    w += std::to_string(s.begin.line);
  }
  return w;
}

[[noreturn]] void fail(const std::string& source, const toml::node& n, const std::string& what) {
  throw std::invalid_argument(where(source, n) + ": " + what);
}

struct Reader {
  const std::string& source;
  const toml::table& table;
  std::string prefix;

  const toml::node* get(const char* key) const { return table.get(key); }
  void str(const char* key, std::string& out) const {
    if (const auto* n = get(key)) {
      if (!n->is_string()) fail(source, *n, prefix + key + ": expected a string");
      out = n->as_string()->get();
    }
  }
  void path(const char* key, std::filesystem::path& out) const {
    std::string s;
    str(key, s);
    if (get(key)) out = s;
  }
  void boolean(const char* key, bool& out) const {
    if (const auto* n = get(key)) {
      if (!n->is_boolean()) fail(source, *n, prefix + key + ": expected true or false");
      out = n->as_boolean()->get();
    }
  }
  double number(const char* key, double dflt, double lo, double hi) const {
    const auto* n = get(key);
    if (!n) return dflt;
    double v = 0;
    if (n->is_integer()) v = double(n->as_integer()->get());
    else if (n->is_floating_point()) v = n->as_floating_point()->get();
    else fail(source, *n, prefix + key + ": expected a number");
    if (!(v >= lo && v <= hi)) {
      std::ostringstream o;
      o << prefix << key << ": " << v << " is out of range [" << lo << ", " << hi << "]";
      fail(source, *n, o.str());
    }
    return v;
  }
  void strings(const char* key, std::vector<std::string>& out) const {
    const auto* n = get(key);
    if (!n) return;
    const auto* arr = n->as_array();
    if (!arr) fail(source, *n, prefix + key + ": expected an array of strings");
    out.clear();
    for (const auto& e : *arr) {
      if (!e.is_string()) fail(source, e, prefix + key + ": expected an array of strings");
      out.push_back(e.as_string()->get());
    }
  }
  void known(std::initializer_list<const char*> keys) const {
    for (const auto& [k, v] : table) {
      bool ok = false;
      for (const char* key : keys) ok = ok || k.str() == key;
      if (!ok) fail(source, v, "unknown key '" + prefix + std::string(k.str()) + "'");
    }
  }
};


// [machine.tool_change]: the same fields as a job's `tool_change` object,
// checked by the same code; a bad one names the file and line.
void read_tool_change(const std::string& source, const toml::node& n, ToolChangeSettings& out) {
  const auto* t = n.as_table();
  if (!t) fail(source, n, "machine.tool_change: expected a table");
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [k, v] : *t) {
    const std::string key(k.str());
    if (v.is_string()) j[key] = v.as_string()->get();
    else if (v.is_integer()) j[key] = double(v.as_integer()->get());
    else if (v.is_floating_point()) j[key] = v.as_floating_point()->get();
    else if (const auto* a = v.as_array()) {
      nlohmann::json arr = nlohmann::json::array();
      for (const auto& e : *a) {
        if (e.is_integer()) arr.push_back(double(e.as_integer()->get()));
        else if (e.is_floating_point()) arr.push_back(e.as_floating_point()->get());
        else fail(source, e, "machine.tool_change." + key + ": expected numbers");
      }
      j[key] = arr;
    } else {
      fail(source, v, "machine.tool_change." + key + ": expected a string, a number or [X, Y]");
    }
  }
  try {
    apply_tool_change_json(out, j, "machine.tool_change.");
  } catch (const ApiError& e) {
    fail(source, n, e.message);
  }
}

bool valid_name(const std::string& n) {
  if (n.empty() || n.size() > 32) return false;
  for (char c : n)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}


}  // namespace

bool DaemonConfig::listen_is_loopback() const {
  const std::string& a = listen_address;
  if (a == "localhost" || a == "::1") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, a.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  return false;
}

std::filesystem::path default_data_dir() {
  if (const char* x = std::getenv("XDG_STATE_HOME"); x && *x) return std::filesystem::path(x) / "cncstream" / "daemon";
  if (const char* h = std::getenv("HOME"); h && *h)
    return std::filesystem::path(h) / ".local" / "state" / "cncstream" / "daemon";
  return std::filesystem::path("cncstream-daemon");
}

std::filesystem::path journal_path(const DaemonConfig& c) {
  if (!c.journal.empty()) return c.journal;
  if (!c.data_dir.empty()) return c.data_dir / "journal.sqlite";
  return transport::Journal::default_path();
}

void apply_listen(DaemonConfig& c, const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
    throw std::invalid_argument("listen '" + text + "': expected ADDR:PORT, e.g. 127.0.0.1:8420");
  std::string addr = text.substr(0, colon);
  if (addr.size() >= 2 && addr.front() == '[' && addr.back() == ']') addr = addr.substr(1, addr.size() - 2);
  const std::string port = text.substr(colon + 1);
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (*end || p < 0 || p > 65535)
    throw std::invalid_argument("listen '" + text + "': the port must be a number from 0 to 65535");
  c.listen_address = addr;
  c.listen_port = static_cast<unsigned short>(p);
}

MachineConfig parse_machine_option(const std::string& text) {
  MachineConfig m;
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument("--machine '" + text + "': expected NAME=PORT[,profile=P,baud=B,sim_speed=S]");
  m.name = text.substr(0, eq);
  std::stringstream rest(text.substr(eq + 1));
  std::string item;
  bool first = true;
  while (std::getline(rest, item, ',')) {
    if (first) {
      m.port = item;
      first = false;
      continue;
    }
    const auto e = item.find('=');
    if (e == std::string::npos) throw std::invalid_argument("--machine '" + text + "': '" + item + "' is not KEY=VALUE");
    const std::string k = item.substr(0, e), v = item.substr(e + 1);
    try {
      if (k == "profile") m.profile = v;
      else if (k == "baud") m.baud = static_cast<unsigned>(std::stoul(v));
      else if (k == "sim_speed") m.sim_speed = v;
      else if (k == "reconnect_s") m.reconnect_s = std::stod(v);
      else if (k == "sim_verify") m.sim_verify = v == "true" || v == "1";
      else throw std::invalid_argument("unknown key");
    } catch (const std::exception&) {
      throw std::invalid_argument("--machine '" + text + "': bad '" + item +
                                  "' (keys: profile, baud, sim_speed, sim_verify, reconnect_s)");
    }
  }
  if (m.port.empty()) throw std::invalid_argument("--machine '" + text + "': no port");
  return m;
}

void validate(const DaemonConfig& c) {
  std::set<std::string> names;
  if (c.machines.empty()) throw std::invalid_argument("no machine configured");
  for (const auto& m : c.machines) {
    if (!valid_name(m.name))
      throw std::invalid_argument("machine name '" + m.name + "': use 1-32 letters, digits, '_' or '-'");
    if (!names.insert(m.name).second) throw std::invalid_argument("machine name '" + m.name + "' is used twice");
    if (m.port.empty()) throw std::invalid_argument("machine '" + m.name + "': no port");
    if (m.baud < 1200 || m.baud > 4'000'000) throw std::invalid_argument("machine '" + m.name + "': baud out of range");
    if (!(m.reconnect_s > 0 && m.reconnect_s <= 3600))
      throw std::invalid_argument("machine '" + m.name + "': reconnect_s must be in (0, 3600]");
  }
  for (const auto& p : c.pendants)
    if (!names.count(p.machine))
      throw std::invalid_argument("pendant: no machine named '" + p.machine + "' (configured: " +
                                  [&] {
                                    std::string all;
                                    for (const auto& m : c.machines) {
                                      if (!all.empty()) all.append(", ");
                                      all.append(m.name);
                                    }
                                    return all;
                                  }() +
                                  ")");
}

DaemonConfig parse_config(std::string_view text, const std::string& source) {
  toml::table root;
  protocol::check_toml_text(text, source);
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream o;
    o << source << ":" << e.source().begin.line << ":" << e.source().begin.column << ": " << e.description();
    throw std::invalid_argument(o.str());
  }
  DaemonConfig c;
  Reader top{source, root, ""};
  top.known({"listen", "data_dir", "journal", "machine", "pendant", "limits", "security", "web", "shop"});
  if (const auto* n = root.get("listen")) {
    if (!n->is_string()) fail(source, *n, "listen: expected \"ADDR:PORT\"");
    try {
      apply_listen(c, n->as_string()->get());
    } catch (const std::invalid_argument& e) {
      fail(source, *n, e.what());
    }
  }
  top.path("data_dir", c.data_dir);
  top.path("journal", c.journal);
  if (const auto* n = root.get("machine")) {
    const auto* arr = n->as_array();
    if (!arr) fail(source, *n, "machine: expected [[machine]] tables");
    c.machines.clear();
    for (const auto& e : *arr) {
      const auto* t = e.as_table();
      if (!t) fail(source, e, "machine: expected a table");
      Reader r{source, *t, "machine."};
      r.known({"name", "port", "baud", "profile", "reconnect_s", "sim_speed", "sim_verify", "sim_vanish_after",
               "sim_settings", "sim_resolution", "sim_tolerance", "sim_tool_table", "sim_tool_sensor",
               "sim_probe_surface_z", "sim_stock", "sim_corner_plate", "sim_start", "sim_firmware", "tool_change",
               "capabilities", "shop_claim"});
      MachineConfig m;
      r.str("name", m.name);
      r.str("port", m.port);
      m.baud = static_cast<unsigned>(r.number("baud", m.baud, 1200, 4'000'000));
      r.str("profile", m.profile);
      m.reconnect_s = r.number("reconnect_s", m.reconnect_s, 0.01, 3600);
      r.str("sim_speed", m.sim_speed);
      r.boolean("sim_verify", m.sim_verify);
      m.sim_vanish_after = static_cast<std::size_t>(r.number("sim_vanish_after", 0, 0, 1e9));
      r.str("sim_settings", m.sim_settings);
      r.str("sim_firmware", m.sim_firmware);
      if (m.sim_firmware != "grbl" && m.sim_firmware != "grblhal")
        fail(source, *r.get("sim_firmware"), "machine.sim_firmware: '" + m.sim_firmware + "' is not grbl or grblhal");
      m.sim_resolution = r.number("sim_resolution", m.sim_resolution, 0.01, 10);
      m.sim_tolerance = r.number("sim_tolerance", m.sim_tolerance, 0.001, 10);
      r.str("sim_tool_table", m.sim_tool_table);
      r.str("sim_tool_sensor", m.sim_tool_sensor);
      if (r.get("sim_probe_surface_z")) m.sim_probe_surface_z = r.number("sim_probe_surface_z", 0, -1e4, 1e4);
      r.str("sim_stock", m.sim_stock);
      r.str("sim_corner_plate", m.sim_corner_plate);
      r.str("sim_start", m.sim_start);
      if (const auto* tc = r.get("tool_change")) read_tool_change(source, *tc, m.tool_change);
      r.strings("capabilities", m.capabilities);
      r.boolean("shop_claim", m.shop_claim);
      c.machines.push_back(m);
    }
  }
  if (const auto* n = root.get("pendant")) {
    const auto* arr = n->as_array();
    if (!arr) fail(source, *n, "pendant: expected [[pendant]] tables");
    for (const auto& e : *arr) {
      const auto* t = e.as_table();
      if (!t) fail(source, e, "pendant: expected a table");
      Reader r{source, *t, "pendant."};
      r.known({"machine", "lease_s", "macros"});
      PendantSection p;
      r.str("machine", p.machine);
      p.lease_s = r.number("lease_s", p.lease_s, 0.05, 2);
      r.strings("macros", p.macros);
      if (p.machine.empty()) fail(source, e, "pendant: name the machine it drives (machine = \"...\")");
      c.pendants.push_back(p);
    }
  }
  if (const auto* n = root.get("limits")) {
    const auto* t = n->as_table();
    if (!t) fail(source, *n, "limits: expected a table");
    Reader r{source, *t, "limits."};
    r.known({"max_upload_bytes", "max_connections", "max_ws_clients", "header_timeout_s", "body_timeout_s",
             "ws_queue_messages", "max_grid_nodes", "control_idle_s", "worker_threads"});
    auto& l = c.limits;
    l.max_upload_bytes = static_cast<std::uint64_t>(r.number("max_upload_bytes", double(l.max_upload_bytes), 1, 1e12));
    l.max_connections = static_cast<std::size_t>(r.number("max_connections", double(l.max_connections), 1, 100000));
    l.max_ws_clients = static_cast<std::size_t>(r.number("max_ws_clients", double(l.max_ws_clients), 1, 100000));
    l.header_timeout_s = r.number("header_timeout_s", l.header_timeout_s, 0.1, 3600);
    l.body_timeout_s = r.number("body_timeout_s", l.body_timeout_s, 0.1, 86400);
    l.ws_queue_messages = static_cast<std::size_t>(r.number("ws_queue_messages", double(l.ws_queue_messages), 4, 1e7));
    l.max_grid_nodes = r.number("max_grid_nodes", l.max_grid_nodes, 1e3, 1e10);
    l.control_idle_s = r.number("control_idle_s", l.control_idle_s, 1, 1e6);
    l.worker_threads = static_cast<unsigned>(r.number("worker_threads", 0, 0, 1024));
  }
  if (const auto* n = root.get("security")) {
    const auto* t = n->as_table();
    if (!t) fail(source, *n, "security: expected a table");
    Reader r{source, *t, "security."};
    r.known({"require_token", "allowed_origins", "allowed_hosts"});
    r.boolean("require_token", c.security.require_token);
    r.strings("allowed_origins", c.security.allowed_origins);
    r.strings("allowed_hosts", c.security.allowed_hosts);
  }
  if (const auto* n = root.get("shop")) {
    const auto* t = n->as_table();
    if (!t) fail(source, *n, "shop: expected a table");
    Reader r{source, *t, "shop."};
    r.known({"url", "name", "pc", "lease_s", "heartbeat_s", "mtconnect_port", "mtconnect_address", "mqtt_host",
             "mqtt_port", "mqtt_username", "mqtt_password", "mqtt_ca_file", "mqtt_keepalive_s"});
    r.str("url", c.shop.url);
    r.str("name", c.shop.name);
    r.str("pc", c.shop.pc);
    c.shop.lease_s = r.number("lease_s", c.shop.lease_s, 0.5, 86400);
    c.shop.heartbeat_s = r.number("heartbeat_s", c.shop.heartbeat_s, 0.1, 3600);
    if (r.get("mtconnect_port"))
      c.shop.mtconnect_port = static_cast<unsigned short>(r.number("mtconnect_port", 7878, 0, 65535));
    r.str("mtconnect_address", c.shop.mtconnect_address);
    r.str("mqtt_host", c.shop.mqtt_host);
    c.shop.mqtt_port = static_cast<unsigned short>(r.number("mqtt_port", c.shop.mqtt_port, 1, 65535));
    r.str("mqtt_username", c.shop.mqtt_username);
    r.str("mqtt_password", c.shop.mqtt_password);
    r.str("mqtt_ca_file", c.shop.mqtt_ca_file);
    c.shop.mqtt_keepalive_s = r.number("mqtt_keepalive_s", c.shop.mqtt_keepalive_s, 1, 3600);
    if (c.shop.url.empty()) fail(source, *n, "shop.url: the hub's postgresql:// URL is required in [shop]");
    if (c.shop.heartbeat_s >= c.shop.lease_s)
      fail(source, *n, "shop.heartbeat_s must be shorter than shop.lease_s (a heartbeat renews the lease)");
  }
  if (const auto* n = root.get("web")) {
    const auto* t = n->as_table();
    if (!t) fail(source, *n, "web: expected a table");
    Reader r{source, *t, "web."};
    r.known({"root"});
    r.path("root", c.web_root);
  }
  try {
    validate(c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return c;
}

DaemonConfig load_config(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::invalid_argument(file.string() + ": cannot read the configuration file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_config(s.str(), file.string());
}

}  // namespace cncstream::daemon
