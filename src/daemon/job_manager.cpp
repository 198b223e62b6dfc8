#include "cncstream/daemon/job_manager.hpp"

#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "cncstream/daemon/auth.hpp"
#include "cncstream/daemon/job_params.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/gcode/tool_change_line.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/tooling/feeds_speeds.hpp"
#include "cncstream/protocol/link_model.hpp"
#include "cncstream/protocol/grbl_settings.hpp"
#include "cncstream/transport/sha256.hpp"

namespace cncstream::daemon {

// The start of a job message that says where the program pauses (a tool change).
constexpr const char* kPausedAt = "paused at line ";

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kCacheEntries = 16;

bool is_final(const std::string& s) {
  return s == "done" || s == "failed" || s == "stopped" || s == "interrupted" || s == "cancelled";
}

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Builds a Program from G-code text: lines, hash, and the file under
// <programs>/<sha>.nc (written whole, then renamed).
std::shared_ptr<Program> make_program(const std::string& text, const fs::path& programs_dir) {
  auto p = std::make_shared<Program>();
  for (auto l : gcode::split_lines(text)) {
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    p->lines.emplace_back(l);
  }
  if (!p->lines.empty() && p->lines.back().empty()) p->lines.pop_back();
  p->total_lines = static_cast<std::int64_t>(p->lines.size());
  p->extent = gcode::program_extent(p->lines);
  p->sha256 = transport::sha256_hex(text);
  p->path = programs_dir / (p->sha256 + ".nc");
  if (!fs::exists(p->path)) {
    const fs::path tmp = programs_dir / (random_token_hex(8) + ".part");
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      out << text;
      if (!out) throw std::runtime_error(tmp.string() + ": cannot write the program");
    }
    fs::rename(tmp, p->path);
  }
  return p;
}

std::shared_ptr<EtaTable> make_eta(const gcode::ProgramTrace& trace, std::size_t lines, const gcode::MotionLimits& limits,
                                   const gcode::StreamLink& link) {
  auto e = std::make_shared<EtaTable>();
  // The ETA over the machine's own link: a program that starves the planner
  // shows the wire's time, not a flattering one.
  const auto ends = gcode::estimate_line_end_times(trace, limits, lines, link);
  e->end_by_line.assign(lines + 1, 0.0);
  for (std::size_t i = 0; i < ends.size() && i + 1 < e->end_by_line.size(); ++i) e->end_by_line[i + 1] = ends[i];
  e->estimated_s = ends.empty() ? 0 : ends.back() + trace.dwell_seconds;
  return e;
}

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error(p.string() + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

JobManager::JobManager(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config,
                       FileStore& files, Machines& machines, WsHub& hub, const fs::path& journal_path,
                       const fs::path& programs_dir)
    : io_(io),
      pool_(pool),
      config_(config),
      files_(files),
      machines_(machines),
      hub_(hub),
      programs_dir_(programs_dir),
      journal_(journal_path),
      tools_(config.data_dir.empty() ? fs::path() : config.data_dir / "tools.toml"),
      previews_(io, pool) {
  fs::create_directories(programs_dir_);
  MachineJobListener l;
  l.started = [this](const std::string& m, std::int64_t id) { on_started(m, id); };
  l.progress = [this](const std::string& m, const protocol::JobProgress& p) { on_progress(m, p); };
  l.state = [this](const std::string& m, const std::string& s) { on_state(m, s); };
  l.holding = [this](const std::string& m, bool holds, long answered) { on_holding(m, holds, answered); };
  l.ended = [this](const std::string& m, protocol::JobOutcome o, long line, const std::string& t) {
    on_ended(m, o, line, t);
  };
  l.verified = [this](const std::string& m, SimVerifyReport r) { on_verified(m, std::move(r)); };
  l.start_failed = [this](const std::string& m, bool, const std::string& why) { on_start_failed(m, why); };
  machines_.set_listener(std::move(l));
  machines_.current_job = [this](const std::string& m) { return current_job(m); };
  machines_.library_tool = [this](const std::string& m, int tool) { return library_tool(m, tool); };
}

json JobManager::library_tool(const std::string& machine, int number) const {
  const tooling::ToolLibrary library = tools_.snapshot();
  const tooling::Tool* t = nullptr;
  const auto run = running_.find(machine);
  const auto job = run == running_.end() ? jobs_.end() : jobs_.find(run->second);
  if (job != jobs_.end() && !job->second->params.is_null()) {
    // A program the daemon generated writes a library tool's own number; a
    // cutter given as a spec keeps its place in the operations' order, which
    // may be another tool's number: the library tool of that number when it
    // has the shape the operation cuts with, else (a spec, a program numbered
    // before the library's numbers were written) the one with that shape.
    const Program* p = job->second->program.get();
    std::optional<cam::Cutter> cutter;
    if (p && p->tools.count(number)) cutter = p->tools.at(number);
    else if (p && p->tools.empty() && number == 1) cutter = p->cutter;
    if (cutter) {
      t = library.by_number(number);
      if (t && t->geometry.spec() != cutter->spec()) t = nullptr;
      for (const auto& candidate : library.tools)
        if (!t && candidate.geometry.spec() == cutter->spec()) t = &candidate;
    }
  } else {
    t = library.by_number(number);  // a G-code file's T numbers are the shop's
  }
  if (!t) return nullptr;
  return {{"number", t->number},
          {"name", t->name},
          {"shape", t->geometry.spec()},
          {"description", t->geometry.description()},
          {"stick_out", t->stick_out > 0 ? json(t->stick_out) : json(nullptr)}};  // 0: not known
}

JobManager::~JobManager() {
  *alive_ = false;
  for (auto& [k, s] : generation_stop_) s->request_stop();
}

void JobManager::recover() {
  for (auto& row : journal_.daemon_jobs(100000)) {
    auto j = std::make_unique<DaemonJob>();
    j->row = row;
    try {
      j->params = row.params_json.empty() ? json(nullptr) : json::parse(row.params_json);
    } catch (const std::exception&) {
      j->params = nullptr;
    }
    // The job's own tool-change settings come back with it: a restart never
    // runs its change with the machine's instead.
    bool tool_change_lost = false;
    try {
      j->tool_change = row.tool_change_json.empty() ? json(nullptr) : json::parse(row.tool_change_json);
    } catch (const std::exception&) {
      tool_change_lost = true;
    }
    j->cache_key = generation_key(row.file_id, j->params, row.machine);
    if (row.state == "running" || row.state == "held") {
      // The daemon died under a running job: the machine may have moved on
      // its buffered lines or stopped; never resume by itself.
      if (row.journal_id)
        if (const auto p = journal_.last_progress(row.journal_id)) j->row.last_line = p->last_line;
      j->row.state = "interrupted";
      j->row.ended_at = transport::Journal::now_iso8601();
      j->row.message = "cncstreamd stopped while this job ran (last answered line " + std::to_string(j->row.last_line) +
                       "); not resumed: check the machine, then plan a resume from the line";
      if (row.journal_id) {
        const auto rec = journal_.job(row.journal_id);
        if (rec && !rec->outcome) journal_.end_job(row.journal_id, "interrupted", j->row.message);
      }
      journal_.update_daemon_job(j->row);
      interrupted_at_recovery_.push_back(row.id);
    } else if (!is_final(row.state) && tool_change_lost) {
      // Fail closed: without its own settings its change would run the machine's.
      j->row.state = "failed";
      j->row.ended_at = transport::Journal::now_iso8601();
      j->row.message = "its tool_change settings could not be read back from the journal after a restart: create it again";
      journal_.update_daemon_job(j->row);
    } else if (!is_final(row.state)) {
      j->row.state = "queued";  // generated again below; never started by itself
      journal_.update_daemon_job(j->row);
    }
    jobs_[row.id] = std::move(j);
  }
  for (auto& [id, j] : jobs_)
    if (j->row.state == "queued") kick_generation(*j);
  spdlog::info("jobs: {} in the journal", jobs_.size());
}

// ---- persistence and publishing ---------------------------------------------

void JobManager::persist(DaemonJob& j) {
  try {
    journal_.update_daemon_job(j.row);
  } catch (const std::exception& e) {
    spdlog::error("journal: {}", e.what());
  }
}

json JobManager::to_json(const DaemonJob& j) const {
  const auto& r = j.row;
  json gen = nullptr;
  if (r.kind == "stl" || j.stage.size())
    gen = {{"stage", j.stage}, {"fraction", j.fraction}, {"cached", j.cached},
           {"seconds", j.program ? json(j.program->seconds) : json(nullptr)}};
  json prog = nullptr;
  const EtaTable* et = eta_table(j);
  if (j.program) {
    json ops = json::array();
    for (const auto& op : j.program->operations)
      ops.push_back({{"name", op.name},
                     {"tool", op.tool},
                     {"cutter", op.cutter.spec()},
                     {"detail", op.detail},
                     {"first_line", op.first_line},
                     {"lines", op.lines},
                     {"feed_time_s", op.feed_time_s},
                     // The feed the machine's link delivers this operation's densest stretch at (null: any)
                     // and the share of its path where F was lowered to it.
                     {"wire_feed", op.link_checked && std::isfinite(op.wire_feed) ? json(op.wire_feed) : json(nullptr)},
                     {"share_below_feed", op.link_checked ? json(op.share_below_feed) : json(nullptr)}});
    prog = {{"lines", j.program->lines.size()},
            {"estimated_s", et ? json(et->estimated_s) : json(nullptr)},
            {"operations", ops},
            {"notes", j.program->notes}};
  }
  json progress = {{"lines_sent", j.progress.lines_sent},
                   {"lines_answered", j.progress.lines_answered},
                   {"last_answered_line", std::max<std::int64_t>(r.last_line, j.progress.last_answered_line)},
                   {"executing_line", j.progress.executing_line},
                   {"fraction", fraction(j)},
                   {"eta_s", eta(j) ? json(*eta(j)) : json(nullptr)}};
  json preview = nullptr;
  if (j.program && j.program->height && !j.program->height->empty()) {
    const auto& h = *j.program->height;
    const cam::XYBounds b = h.bounds();
    const auto r4 = [](double v) { return std::round(v * 1e4) / 1e4; };
    const std::string base = cat({"/api/v1/jobs/", std::to_string(r.id)});
    preview = {{"bounds", {r4(b.x0), r4(b.y0), r4(b.x1), r4(b.y1)}},
               {"z", {r4(h.z_min), r4(h.z_max)}},
               {"png", cat({base, "/clmap.png"})},
               {"path", cat({base, "/path"})}};
  }
  json verify = nullptr;
  if (j.verify)
    verify = {{"gouged", j.verify->gouged},
              {"largest_gouge_mm", j.verify->largest_gouge_mm ? json(*j.verify->largest_gouge_mm) : json(nullptr)},
              {"text", j.verify->text}};
  return {{"id", r.id},
          {"machine", r.machine},
          {"file", r.file_id},
          {"file_name", r.file_name},
          {"kind", r.kind},
          {"params", j.params},
          {"state", r.state},
          {"position", r.position},
          {"message", r.message},
          {"created_at", r.created_at},
          {"started_at", r.started_at ? json(*r.started_at) : json(nullptr)},
          {"ended_at", r.ended_at ? json(*r.ended_at) : json(nullptr)},
          {"generation", gen},
          {"program", prog},
          {"progress", progress},
          {"preview", preview},
          {"verify", verify},
          {"journal_id", r.journal_id ? json(r.journal_id) : json(nullptr)},
          {"resumed_from", r.resumed_from},
          {"from_line", r.from_line},
          {"tool_change", j.tool_change}};
}

const EtaTable* JobManager::eta_table(const DaemonJob& j) const {
  if (!j.program) return nullptr;
  const auto it = etas_.find(j.program->sha256);
  return it == etas_.end() ? nullptr : it->second.get();
}

std::optional<double> JobManager::eta(const DaemonJob& j) const {
  if (j.row.state == "done") return 0.0;
  const EtaTable* t = eta_table(j);
  if (!t || t->end_by_line.empty()) return std::nullopt;
  const auto& e = t->end_by_line;
  if (j.row.state != "running" && j.row.state != "held") return t->estimated_s;
  const auto line = static_cast<std::size_t>(std::clamp<long>(j.progress.executing_line, 0, long(e.size()) - 1));
  return std::max(0.0, e.back() - e[line]);
}

// The share of the program that has run: the executing line (answered lines
// less the controller's planner queue), not the answered ones, which run
// ahead of the motion by up to a planner's worth of moves.
double JobManager::fraction(const DaemonJob& j) const {
  if (j.row.state == "done") return 1.0;
  const double total = j.program ? double(j.program->total_lines) : 0;
  if (total <= 0) return 0.0;
  // Lines are the program's own (a resumed job's keep their numbers), and a
  // resumed job has done the lines up to the one it continues after.
  const long done = std::max<long>(j.progress.executing_line - 1, j.resume ? j.row.from_line : 0);
  return std::clamp(double(done) / total, 0.0, 1.0);
}

void JobManager::publish_job(const DaemonJob& j) {
  json f = to_json(j);
  json m = {{"type", "job"},     {"job", j.row.id},         {"machine", j.row.machine}, {"state", j.row.state},
            {"progress", f["progress"]}, {"eta_s", f["progress"]["eta_s"]}, {"message", j.row.message},
            {"generation", f["generation"]}, {"verify", f["verify"]}};
  hub_.publish(j.row.machine, WsHub::frame(dump_json(m)));
}

std::vector<DaemonJob*> JobManager::unfinished(const std::string& machine) {
  std::vector<DaemonJob*> v;
  for (auto& [id, j] : jobs_)
    if (j->row.machine == machine && !is_final(j->row.state)) v.push_back(j.get());
  std::sort(v.begin(), v.end(), [](auto* a, auto* b) {
    return a->row.position != b->row.position ? a->row.position < b->row.position : a->row.id < b->row.id;
  });
  return v;
}

void JobManager::publish_queue(const std::string& machine) {
  json list = json::array();
  for (auto* j : unfinished(machine))
    list.push_back({{"id", j->row.id}, {"state", j->row.state}, {"position", j->row.position},
                    {"file_name", j->row.file_name}});
  hub_.publish(machine, WsHub::frame(dump_json(json{{"type", "queue"}, {"machine", machine}, {"jobs", list}})));
}

void JobManager::set_state(DaemonJob& j, const std::string& state, const std::string& message) {
  const bool changed = j.row.state != state;
  j.row.state = state;
  if (!message.empty()) j.row.message = message;
  if (is_final(state) && !j.row.ended_at) j.row.ended_at = transport::Journal::now_iso8601();
  persist(j);
  publish_job(j);
  if (changed) publish_queue(j.row.machine);
  if (changed && on_state_change) on_state_change(j);
}

bool JobManager::has_unfinished(const std::string& machine) const {
  for (const auto& [id, j] : jobs_)
    if (j->row.machine == machine && !is_final(j->row.state)) return true;
  return false;
}

// ---- create, list ---------------------------------------------------------

json JobManager::create(const json& body, std::optional<ShopResume> shop_resume) {
  if (!body.is_object()) throw ApiError{400, "bad_request", "expected a JSON object"};
  if (!body.contains("machine") || !body["machine"].is_string())
    throw ApiError{400, "bad_request", "machine: required, a machine name"};
  if (!body.contains("file") || !body["file"].is_string())
    throw ApiError{400, "bad_request", "file: required, the id of an uploaded file"};
  const std::string machine = body["machine"].get<std::string>();
  if (!machines_.find(machine)) throw ApiError{404, "not_found", "no machine '" + machine.substr(0, 64) + "'"};
  const std::string file_id = body["file"].get<std::string>();
  const auto info = files_.get(file_id);
  if (!info) throw ApiError{404, "not_found", "no file '" + file_id.substr(0, 64) + "'"};
  auto j = std::make_unique<DaemonJob>();
  if (body.contains("tool_change") && !body["tool_change"].is_null()) {
    ToolChangeSettings check = machines_.find(machine)->config.tool_change;
    apply_tool_change_json(check, body["tool_change"], "tool_change.");  // a 400 naming the field
    j->tool_change = body["tool_change"];
  }
  if (info->kind == "stl") {
    if (!body.contains("params")) throw ApiError{400, "bad_request", "params: required for an STL file (at least tool)"};
    // The machine's $$ bounds the feeds and speeds a material gives: its
    // rates, and a real controller's spindle $30/$31 (the simulator's are
    // GRBL's shipped PWM scale, not a spindle's).
    tooling::MachineLimits machine_limits;
    if (Machine* m = machines_.find(machine))
      machine_limits = tooling::machine_limits_from_settings(m->session->settings(), m->config.port != "sim");
    const tooling::ToolLibrary library = tools_.snapshot();
    const auto checked = check_toolpath_params(body["params"], *info, config_.limits, &library, machine_limits);
    j->params = checked.canonical;
  } else {
    j->params = nullptr;
  }
  j->cache_key = generation_key(file_id, j->params, machine);
  auto& r = j->row;
  r.machine = machine;
  r.file_id = file_id;
  r.file_name = info->name;
  r.kind = info->kind;
  r.params_json = j->params.is_null() ? "" : j->params.dump();
  r.tool_change_json = j->tool_change.is_null() ? "" : j->tool_change.dump();
  r.state = "queued";
  std::int64_t pos = 0;
  for (auto* u : unfinished(machine)) pos = std::max(pos, u->row.position + 1);
  r.position = pos;
  r.created_at = transport::Journal::now_iso8601();
  if (shop_resume) {
    if (shop_resume->after_line <= 0) throw ApiError{400, "bad_request", "a resume needs the line it continues after (> 0)"};
    // Recorded at once: a daemon restart before the plan is made fails the
    // job (kick_generation) rather than run it from the top.
    r.resumed_from = shop_resume->ran_as;
    r.from_line = shop_resume->after_line;
    r.message = "a resume after line " + std::to_string(shop_resume->after_line) + ", planned once the program is ready";
    j->shop_resume = shop_resume;
  }
  r.id = journal_.insert_daemon_job(r);
  auto& ref = *j;
  jobs_[r.id] = std::move(j);
  spdlog::info("job {}: created on {} from {} ({})", r.id, machine, info->name, info->kind);
  publish_queue(machine);
  kick_generation(ref);
  return to_json(ref);
}

json JobManager::list(const std::optional<std::string>& machine, const std::optional<std::string>& state) const {
  std::vector<const DaemonJob*> open, done;
  for (const auto& [id, j] : jobs_) {
    if (machine && j->row.machine != *machine) continue;
    if (state && j->row.state != *state) continue;
    (is_final(j->row.state) ? done : open).push_back(j.get());
  }
  std::sort(open.begin(), open.end(), [](auto* a, auto* b) {
    return a->row.position != b->row.position ? a->row.position < b->row.position : a->row.id < b->row.id;
  });
  std::sort(done.begin(), done.end(), [](auto* a, auto* b) { return a->row.id > b->row.id; });
  json out = json::array();
  for (auto* j : open)
    if (out.size() < 200) out.push_back(to_json(*j));
  for (auto* j : done)
    if (out.size() < 200) out.push_back(to_json(*j));
  return {{"jobs", out}};
}

DaemonJob& JobManager::get(std::int64_t id) {
  const auto it = jobs_.find(id);
  if (it == jobs_.end()) throw ApiError{404, "not_found", "no job " + std::to_string(id)};
  return *it->second;
}

Machine& JobManager::machine_of(const DaemonJob& j) {
  Machine* m = machines_.find(j.row.machine);
  if (!m) throw ApiError{409, "bad_state", "job " + std::to_string(j.row.id) + "'s machine '" + j.row.machine +
                                               "' is not configured any more"};
  return *m;
}

DaemonJob* JobManager::running_on(const std::string& machine) {
  const auto it = running_.find(machine);
  if (it == running_.end()) return nullptr;
  const auto j = jobs_.find(it->second);
  return j == jobs_.end() ? nullptr : j->second.get();
}

bool JobManager::file_in_use(const std::string& file_id) const {
  for (const auto& [id, j] : jobs_)
    if (j->row.file_id == file_id && !is_final(j->row.state)) return true;
  return false;
}

json JobManager::current_job(const std::string& machine) const {
  const auto it = running_.find(machine);
  if (it == running_.end()) return nullptr;
  return it->second;
}

// ---- generation -------------------------------------------------------------

void JobManager::cache_put(const std::string& key, std::shared_ptr<const Program> p) {
  cache_.remove_if([&](const auto& e) { return e.first == key; });
  cache_.emplace_back(key, std::move(p));
  while (cache_.size() > kCacheEntries) cache_.pop_front();
}

std::string JobManager::generation_key(const std::string& file_id, const json& params, const std::string& machine) {
  if (params.is_null()) return file_id + ":gcode";
  // The same part for machines on different links is a different program (F lowered where each wire is short).
  const Machine* m = machines_.find(machine);
  const double rate = (m ? machine_link(m->config) : protocol::grbl_default_link()).bytes_per_second;
  return fmt::format("{}:{}:link={:.0f}", file_id, params.dump(), rate);
}

void JobManager::kick_generation(DaemonJob& j) {
  if ((j.row.resumed_from || j.row.from_line) && !j.resume && !j.shop_resume) {
    // A confirmed resume whose lines were lost with a restart: plan it again from its recorded line.
    set_state(j, "failed", "the resume plan was lost with a daemon restart: plan the resume again from job " +
                               std::to_string(j.row.resumed_from));
    return;
  }
  for (auto it = cache_.begin(); it != cache_.end(); ++it) {
    if (it->first != j.cache_key) continue;
    j.program = it->second;
    cache_.splice(cache_.end(), cache_, it);  // most recently used
    j.cached = true;
    j.stage = "done";
    j.fraction = 1;
    program_ready(j);
    return;
  }
  j.cached = false;
  j.stage = "queued";
  j.fraction = 0;
  set_state(j, "generating");
  auto& waiting = generating_[j.cache_key];
  waiting.push_back(j.row.id);
  if (waiting.size() > 1) return;  // the same program is being generated for another job

  auto stop = std::make_shared<std::stop_source>();
  generation_stop_[j.cache_key] = stop;
  const auto path = files_.content_path(j.row.file_id);
  if (!path) {
    generating_.erase(j.cache_key);
    generation_stop_.erase(j.cache_key);
    set_state(j, "failed", "the file " + j.row.file_id + " was deleted");
    return;
  }
  gcode::MotionLimits limits = protocol::grbl_default_motion_limits();
  gcode::StreamLink link = protocol::grbl_default_link();
  if (Machine* m = machines_.find(j.row.machine)) {
    if (auto l = protocol::motion_limits_from(m->session->settings())) limits = *l;
    link = machine_link(m->config);
  }
  jobs::ToolpathParams params;
  const bool stl = j.row.kind == "stl";
  if (stl) {
    auto info = files_.get(j.row.file_id);
    if (!info) info = FileInfo{};
    params = check_toolpath_params(j.params, *info, config_.limits).params;
    params.part.stl = path->string();
    params.link = link;  // F lowered where the machine's wire cannot keep up (the plan says where)
  }
  const std::string key = j.cache_key;
  const std::string label = j.row.file_name;
  struct Shared {
    std::atomic<int> last_percent{-1};
  };
  auto shared = std::make_shared<Shared>();
  boost::asio::post(pool_, [this, key, label, stl, params, limits, link, file = *path, stop, shared, alive = alive_] {
    std::shared_ptr<Program> prog;
    std::string text;
    std::string error;
    bool cancelled = false;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      if (stl) {
        jobs::JobControl control;
        control.stop = stop->get_token();
        control.progress = [this, key, shared, alive](std::string_view stage, double f) {
          const int pct = static_cast<int>(f * 100);
          if (pct == shared->last_percent.exchange(pct)) return;
          boost::asio::post(io_, [this, key, st = std::string(stage), f, alive] {
            if (!*alive) return;
            const auto it = generating_.find(key);
            if (it == generating_.end()) return;
            for (auto id : it->second)
              if (auto j = jobs_.find(id); j != jobs_.end()) {
                j->second->stage = st;
                j->second->fraction = f;
                publish_job(*j->second);
              }
          });
        };
        auto r = jobs::generate_toolpath(params, control);
        text = std::move(r.gcode);
        prog = make_program(text, programs_dir_);
        prog->work_mesh = std::move(r.work_mesh);
        prog->cutter = r.cutter;
        if (r.operations.size() > 1)
          for (const auto& op : r.operations) prog->tools[op.tool] = op.cutter;
        prog->operations = r.operations;
        prog->stock = r.stock;
        prog->notes = r.notes;
        prog->height = std::make_shared<const jobs::HeightPreview>(std::move(r.preview));
      } else {
        text = read_all(file);
        prog = make_program(text, programs_dir_);
      }
      prog->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } catch (const jobs::Cancelled&) {
      cancelled = true;
    } catch (const std::exception& e) {
      error = label + ": " + e.what();
    }
    boost::asio::post(io_, [this, key, prog, error, cancelled, alive] {
      if (*alive) on_generated(key, prog, error, cancelled);
    });
    if (!prog || stop->stop_requested()) return;
    // The ETA table (and a G-code program's preview heights) after the job
    // is ready: tracing the program takes a while for a big one, and nothing
    // waits for it.
    try {
      const auto trace = gcode::trace_program(text);
      auto eta = make_eta(trace, prog->lines.size(), limits, link);
      std::shared_ptr<const jobs::HeightPreview> height;
      if (!stl) height = std::make_shared<const jobs::HeightPreview>(jobs::height_preview_from_trace(trace));
      boost::asio::post(io_, [this, prog, eta, height, alive] {
        if (!*alive) return;
        if (height && !prog->height) prog->height = height;
        const std::string& sha = prog->sha256;
        etas_[sha] = eta;
        if (etas_.size() > 64) etas_.erase(etas_.begin());
        for (auto& [id, j] : jobs_)
          if (j->program && j->program->sha256 == sha && !is_final(j->row.state)) publish_job(*j);
      });
    } catch (const std::exception& e) {
      spdlog::warn("{}: no time estimate: {}", label, e.what());
    }
  });
}

void JobManager::on_generated(const std::string& key, const std::shared_ptr<const Program>& p,
                              const std::string& error, bool cancelled) {
  auto waiting = std::move(generating_[key]);
  generating_.erase(key);
  generation_stop_.erase(key);
  if (p) cache_put(key, p);
  for (auto id : waiting) {
    auto it = jobs_.find(id);
    if (it == jobs_.end()) continue;
    auto& j = *it->second;
    if (j.row.state != "generating") continue;  // cancelled meanwhile
    if (p) {
      j.program = p;
      j.stage = "done";
      j.fraction = 1;
      spdlog::info("job {}: ready: {} lines in {:.3f} s", id, p->lines.size(), p->seconds);
      program_ready(j);
    } else if (cancelled) {
      set_state(j, "cancelled", "generation cancelled");
    } else {
      spdlog::warn("job {}: generation failed: {}", id, error);
      set_state(j, "failed", error);
    }
  }
}

json JobManager::generate(std::int64_t id) {
  auto& j = get(id);
  if (j.row.state != "queued")
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + j.row.state + ", not queued"};
  kick_generation(j);
  return to_json(j);
}

// ---- preview ----------------------------------------------------------------

std::shared_ptr<const Program> JobManager::program_for_preview(std::int64_t id) {
  const auto& j = get(id);
  if (!j.program)
    throw ApiError{409, "bad_state", cat({"job ", std::to_string(id), " has no program yet (", j.row.state, ")"})};
  return j.program;
}

void JobManager::preview_png(std::int64_t id, int max_px, Respond respond) {
  previews_.png(program_for_preview(id), max_px, std::move(respond));
}

void JobManager::preview_path(std::int64_t id, std::size_t max_points, Respond respond) {
  previews_.path(program_for_preview(id), max_points, std::move(respond));
}

// ---- running ----------------------------------------------------------------

json JobManager::start(std::int64_t id, const std::string& client) {
  auto& j = get(id);
  Machine& m = machine_of(j);
  machines_.require_control(m, client);
  if (j.row.state != "ready")
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + j.row.state + "; only a ready job starts"};
  if (auto* r = running_on(j.row.machine))
    throw ApiError{409, "refused", "job " + std::to_string(r->row.id) + " is running on " + j.row.machine};
  session::JobInput in;
  in.file = j.program->path;
  in.file_sha256 = j.program->sha256;
  in.total_lines = j.program->total_lines;
  in.extent = j.program->extent;
  if (j.resume) {
    in.lines = j.resume->lines;
    in.source_lines = j.resume->source_lines;
    in.resumed_from = j.row.resumed_from;
    in.from_line = j.resume->from_line;
  } else {
    in.lines = j.program->lines;
  }
  std::optional<geometry::Mesh> design;
  std::optional<cam::Cutter> cutter;
  std::map<int, cam::Cutter> tools;
  std::optional<geometry::Box3> stock;
  if (!j.resume && j.program->work_mesh && j.program->cutter) {
    design = j.program->work_mesh;
    cutter = j.program->cutter;
    tools = j.program->tools;
    stock = j.program->stock;
  }
  // The job's tool-change routine: the machine's settings, then the job's own.
  {
    ToolChangeSettings tc = m.config.tool_change;
    if (!j.tool_change.is_null()) apply_tool_change_json(tc, j.tool_change, "tool_change.");
    std::optional<protocol::ToolChangeConfig> routine;
    try {
      routine = routine_config(tc, !gcode::find_tool_changes(in.lines).empty());
    } catch (const std::invalid_argument& e) {
      throw ApiError{409, "refused", cat({"job ", std::to_string(id), ": ", e.what()})};
    }
    if (auto r = m.session->set_tool_change(routine); !r) throw ApiError{409, "refused", r.reason};
  }
  // Marked running before the call: a session that starts at once reports
  // JobStarted from inside start_job.
  running_[j.row.machine] = id;
  last_run_[j.row.machine] = id;
  j.progress = {};
  j.verify.reset();
  const auto r = machines_.start_job(m, std::move(in), std::move(design), cutter, std::move(tools), stock);
  if (!r) {
    running_.erase(j.row.machine);
    throw ApiError{409, "refused", r.reason};
  }
  j.row.started_at = transport::Journal::now_iso8601();
  j.row.message.clear();
  spdlog::info("job {}: started on {} by {}", id, j.row.machine, client);
  set_state(j, "running");
  return to_json(j);
}

void JobManager::hold(std::int64_t id) {
  auto& j = get(id);
  if (j.row.state != "running") throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + j.row.state};
  if (auto r = machine_of(j).session->hold(); !r) throw ApiError{409, "refused", r.reason};
}

void JobManager::resume(std::int64_t id, const std::string& client) {
  auto& j = get(id);
  Machine& m = machine_of(j);
  machines_.require_control(m, client);
  // A program pause (the M0 of a tool change) holds the machine while the
  // job stays running; resume is its cycle start.
  const auto status = m.session->status();
  const bool program_pause = j.row.state == "running" && status && status->state == protocol::MachineState::Hold;
  if (j.row.state != "held" && !program_pause)
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + j.row.state};
  if (auto r = m.session->resume(); !r) throw ApiError{409, "refused", r.reason};
  if (program_pause && j.row.message.starts_with(kPausedAt)) {
    j.row.message.clear();  // the pause is over
    publish_job(j);
  }
}

void JobManager::stop(std::int64_t id) {
  auto& j = get(id);
  if (j.row.state != "running" && j.row.state != "held")
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + j.row.state + "; cancel a job that has not started"};
  if (auto r = machine_of(j).session->stop(); !r) throw ApiError{409, "refused", r.reason};
}

json JobManager::cancel(std::int64_t id, const std::string& client) {
  auto& j = get(id);
  machines_.require_control(machine_of(j), client);
  const auto& s = j.row.state;
  if (s != "queued" && s != "generating" && s != "ready")
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + s + (s == "running" || s == "held" ? "; stop it instead" : "")};
  cancel_waiting(j, "cancelled by " + (client.empty() ? std::string("a client") : client));
  return to_json(j);
}

bool JobManager::cancel_for_shop(std::int64_t id) {
  auto& j = get(id);
  const auto& s = j.row.state;
  if (s != "queued" && s != "generating" && s != "ready") return false;
  cancel_waiting(j, "cancelled on the shop's hub");
  return true;
}

// A job that has not started: its generation stopped if nobody else waits on it.
void JobManager::cancel_waiting(DaemonJob& j, const std::string& message) {
  if (j.row.state == "generating") {
    auto& waiting = generating_[j.cache_key];
    std::erase(waiting, j.row.id);
    if (waiting.empty())
      if (auto st = generation_stop_.find(j.cache_key); st != generation_stop_.end()) st->second->request_stop();
  }
  set_state(j, "cancelled", message);
}

json JobManager::move(std::int64_t id, std::int64_t position) {
  auto& j = get(id);
  if (is_final(j.row.state)) throw ApiError{409, "bad_state", "job " + std::to_string(id) + " has ended"};
  auto list = unfinished(j.row.machine);
  std::erase(list, &j);
  position = std::clamp<std::int64_t>(position, 0, static_cast<std::int64_t>(list.size()));
  list.insert(list.begin() + position, &j);
  for (std::size_t i = 0; i < list.size(); ++i) {
    list[i]->row.position = static_cast<std::int64_t>(i);
    persist(*list[i]);
  }
  publish_queue(j.row.machine);
  return to_json(j);
}

// ---- machine events ---------------------------------------------------------

void JobManager::on_started(const std::string& machine, std::int64_t journal_id) {
  if (auto* j = running_on(machine)) {
    j->row.journal_id = journal_id;
    persist(*j);
  }
}

void JobManager::on_progress(const std::string& machine, const protocol::JobProgress& p) {
  if (auto* j = running_on(machine)) {
    j->progress = p;
    j->row.last_line = p.last_answered_line;
    publish_job(*j);
  }
}

void JobManager::on_holding(const std::string& machine, bool holds, long answered) {
  auto* j = running_on(machine);
  if (!j || !j->program) return;
  if (!holds) {
    // Moving again (cycle start from here, the pendant or the panel): the pause's message is over.
    if (j->row.message.starts_with(kPausedAt)) {
      j->row.message.clear();
      publish_job(*j);
    }
    return;
  }
  static const std::vector<long> kNoSourceLines;
  const auto& lines = j->resume ? j->resume->lines : j->program->lines;
  const auto& sources = j->resume ? j->resume->source_lines : kNoSourceLines;
  const auto pause = session::pause_at(lines, sources, answered);
  if (!pause) return;
  // The program asks something of the operator (a tool change): say it
  // where the job is shown; resume (cycle start) goes on.
  std::string msg = cat({kPausedAt, std::to_string(pause->line), ": ",
                         pause->note.empty() ? std::string("program pause (M0)") : pause->note,
                         " (resume to go on)"});
  if (j->row.message == msg) return;
  spdlog::info("job {}: {}", j->row.id, msg);
  j->row.message = std::move(msg);
  publish_job(*j);
}

void JobManager::on_state(const std::string& machine, const std::string& state) {
  if (auto* j = running_on(machine); j && j->row.state != state) set_state(*j, state);
}

void JobManager::on_ended(const std::string& machine, protocol::JobOutcome o, long last_line, const std::string& text) {
  auto* j = running_on(machine);
  if (!j) return;
  running_.erase(machine);
  if (Machine* m = machines_.find(machine); m && m->session->engine()) j->progress = m->session->engine()->progress();
  j->row.last_line = last_line;
  using protocol::JobOutcome;
  std::string state = "failed";
  std::string msg = text;
  switch (o) {
    case JobOutcome::Completed: state = "done"; break;
    case JobOutcome::Stopped: state = "stopped"; break;
    case JobOutcome::Disconnected:
      state = "interrupted";
      msg = "the machine's port went away at line " + std::to_string(last_line) +
            " (" + text + "); not resumed: check the machine, then plan a resume";
      break;
    default: break;
  }
  set_state(*j, state, msg);
}

void JobManager::on_verified(const std::string& machine, SimVerifyReport rep) {
  const auto it = last_run_.find(machine);
  if (it == last_run_.end()) return;
  auto jt = jobs_.find(it->second);
  if (jt == jobs_.end()) return;
  auto& j = *jt->second;
  spdlog::info("job {}: simulator verify: {}", j.row.id,
               rep.gouged ? "GOUGED" : "no gouge");
  j.verify = std::move(rep);
  j.row.message += (j.row.message.empty() ? "" : "; ") +
                   std::string(j.verify->gouged ? "simulated cut: gouged" : "simulated cut: no gouge");
  persist(j);
  publish_job(j);
}

void JobManager::on_start_failed(const std::string& machine, const std::string& why) {
  if (auto* j = running_on(machine)) {
    running_.erase(machine);
    set_state(*j, "failed", "could not start: " + why);
  }
}

// ---- resume from a line -----------------------------------------------------

// Plans on the pool (tracing a big program takes a while); `done` gets the
// plan, or why there is none, on the event loop while this still exists.
void JobManager::plan_resume_async(jobs::ResumeInput in, ResumePlanned done) {
  boost::asio::post(pool_, [this, in = std::move(in), done = std::move(done), alive = alive_]() mutable {
    std::optional<jobs::ResumePlan> plan;
    std::string error;
    try {
      plan = jobs::plan_resume(in);
    } catch (const std::exception& e) {
      error = e.what();
    }
    boost::asio::post(io_, [plan = std::move(plan), error, done = std::move(done), alive]() mutable {
      if (*alive) done(std::move(plan), error);
    });
  });
}

jobs::ResumeInput JobManager::resume_input(const Program& p, const transport::DaemonJobRow& ran) const {
  jobs::ResumeInput in;
  in.file = p.path;
  in.file_sha256 = p.sha256;
  in.lines = p.lines;
  in.last_line = ran.last_line;
  if (!ran.journal_id) return in;
  const auto rec = journal_.job(ran.journal_id);
  // Another program's journal (a part generated differently) says nothing about this one.
  if (rec && !rec->file_sha256.empty() && rec->file_sha256 != p.sha256) return in;
  if (const auto pr = journal_.last_progress(ran.journal_id)) {
    in.last_line = pr->last_line;
    if (pr->status_work_pos)
      in.status_work_pos = geometry::Vec3{(*pr->status_work_pos)[0], (*pr->status_work_pos)[1], (*pr->status_work_pos)[2]};
    in.status_line = pr->status_line;
  }
  // As `cncstream resume` reads it: the planner depth the job streamed
  // with, the resume it continued, and the lines the controller refused.
  if (rec) {
    in.planner_blocks = static_cast<int>(rec->planner_blocks);
    if (rec->resumed_from > 0) in.resumed_after = rec->from_line;
  }
  in.error_lines = journal_.progress_lines(ran.journal_id, "error");
  return in;
}

void JobManager::program_ready(DaemonJob& j) {
  if (!j.shop_resume) {
    set_state(j, "ready");
    return;
  }
  // A shop job requeued on this machine: ready only as a resume. Its line is
  // the hub's last reported one; an `ok` only means the controller planned
  // a line, so the continuation is chosen as `cncstream resume` chooses it
  // (from the earlier run's journal when this daemon holds it: its status
  // report and planner depth; else backing off the planner's depth).
  const ShopResume sr = *j.shop_resume;
  transport::DaemonJobRow ran;
  if (sr.ran_as)
    if (const auto it = jobs_.find(sr.ran_as); it != jobs_.end() && it->second->row.machine == j.row.machine)
      ran = it->second->row;
  jobs::ResumeInput in = resume_input(*j.program, ran);
  // The hub's line is where it resumes from: a status report that came
  // after it (this journal ran further than it shipped) does not move the
  // choice later; backing off from the hub's line only cuts air twice.
  in.last_line = sr.after_line;
  if (in.status_line > sr.after_line) {
    in.status_work_pos.reset();
    in.status_line = 0;
  }
  in.from_line = -1;
  if (j.row.state != "generating") set_state(j, "generating");
  j.stage = "planning the resume";
  publish_job(j);
  plan_resume_async(std::move(in), [this, id = j.row.id, sr](std::optional<jobs::ResumePlan> plan, const std::string& error) {
    const auto it = jobs_.find(id);
    if (it == jobs_.end() || it->second->row.state != "generating") return;  // cancelled meanwhile
    auto& j = *it->second;
    j.shop_resume.reset();
    if (!plan) {
      set_state(j, "failed", fmt::format("the resume after line {} cannot be planned: {}", sr.after_line, error));
      return;
    }
    j.row.from_line = plan->from_line;
    j.stage = "done";
    j.resume = std::move(*plan);
    spdlog::info("job {}: a shop resume after line {} (the hub's line {}): {}", id, j.resume->from_line, sr.after_line,
                 j.resume->reason);
    set_state(j, "ready", fmt::format("resumes after line {} (the machine last reported line {}): {}",
                                      j.resume->from_line, sr.after_line, j.resume->reason));
  });
}


void JobManager::resume_plan(std::int64_t id, long from_line, const std::string& client,
                             const Respond& respond) {
  auto& j = get(id);
  machines_.require_control(machine_of(j), client);
  const auto& s = j.row.state;
  // A ready or finished job too: the operator starts it from a line (the web page's "continue after line").
  if (s != "stopped" && s != "failed" && s != "interrupted" && s != "ready" && s != "done")
    throw ApiError{409, "bad_state", "job " + std::to_string(id) + " is " + s +
                                         "; resume plans are for ready, done, stopped, failed or interrupted jobs"};
  if (s == "ready" && from_line < 0)
    throw ApiError{400, "bad_request", "from_line: a job that has not run needs the line to continue after (>= 0)"};
  if (!j.program) {
    // After a restart: find the program by its key in the cache, else it must be generated first.
    for (auto& e : cache_)
      if (e.first == j.cache_key) j.program = e.second;
  }
  if (!j.program && j.row.journal_id) {
    // The program the journal recorded is on disk under <data>/programs.
    const auto rec = journal_.job(j.row.journal_id);
    if (rec && fs::exists(rec->file)) {
      try {
        auto p = make_program(read_all(rec->file), programs_dir_);
        j.program = p;
      } catch (const std::exception&) {
      }
    }
  }
  if (!j.program) throw ApiError{409, "bad_state", "job " + std::to_string(id) + "'s program is not available"};
  jobs::ResumeInput in = resume_input(*j.program, j.row);
  in.from_line = from_line;
  if (from_line > j.program->total_lines)
    throw ApiError{400, "bad_request", "from_line " + std::to_string(from_line) + " is past the program's " +
                                           std::to_string(j.program->total_lines) + " lines"};
  plan_resume_async(std::move(in), [this, id, client, respond](std::optional<jobs::ResumePlan> plan,
                                                               const std::string& error) {
    if (!plan) {
      respond(Response::error(400, "bad_request", error));
      return;
    }
    const std::string plan_id = random_token_hex(12);
    json r = {{"plan_id", plan_id}, {"job", id},          {"from_line", plan->from_line}, {"reason", plan->reason},
              {"preamble", plan->preamble}, {"lines", plan->lines.size()}, {"expires_in_s", 600}};
    // The tool the job goes on with: the operator mounts it before confirming.
    if (const auto& op = plan->operation)
      r["operation"] = {{"number", op->number}, {"name", op->name}, {"tool", op->tool}, {"cutter", op->cutter}};
    std::erase_if(plans_, [now = steady_s()](const auto& e) { return e.second.expires < now; });
    plans_[plan_id] = PendingPlan{id, client, std::move(*plan), steady_s() + 600};
    respond(Response::json(200, r));
  });
}

json JobManager::resume_confirm(std::int64_t id, const std::string& plan_id, const std::string& client) {
  auto& old = get(id);
  machines_.require_control(machine_of(old), client);
  const auto it = plans_.find(plan_id);
  if (it == plans_.end() || it->second.job != id || it->second.expires < steady_s())
    throw ApiError{404, "not_found", "no resume plan '" + plan_id.substr(0, 64) + "' for job " + std::to_string(id) +
                                         " (plans expire after 600 s)"};
  auto j = std::make_unique<DaemonJob>();
  j->row = old.row;
  j->row.id = 0;
  j->row.state = "ready";
  j->row.message = "resumes job " + std::to_string(id) + " after line " + std::to_string(it->second.plan.from_line);
  j->row.created_at = transport::Journal::now_iso8601();
  j->row.started_at.reset();
  j->row.ended_at.reset();
  j->row.journal_id = 0;
  j->row.last_line = 0;
  j->row.resumed_from = id;
  j->row.from_line = it->second.plan.from_line;
  std::int64_t pos = 0;
  for (auto* u : unfinished(old.row.machine)) pos = std::max(pos, u->row.position + 1);
  j->row.position = pos;
  j->params = old.params;
  j->tool_change = old.tool_change;
  j->cache_key = old.cache_key;
  j->program = old.program;
  j->resume = std::move(it->second.plan);
  j->stage = "done";
  j->fraction = 1;
  plans_.erase(it);
  j->row.id = journal_.insert_daemon_job(j->row);
  auto& ref = *j;
  jobs_[ref.row.id] = std::move(j);
  publish_queue(ref.row.machine);
  publish_job(ref);
  return to_json(ref);
}

}  // namespace cncstream::daemon
