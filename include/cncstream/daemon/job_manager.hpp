#pragma once
// The daemon's jobs: the queue per machine, their states, tool-path
// generation on the worker pool with a cache keyed by (file hash,
// parameters), starting and controlling a job on its machine, the resume
// planner, and the rows in the shared SQLite journal that let the queue and
// the history survive a restart. Runs on the event loop's thread; only
// generation and resume planning run on the pool.
#include <boost/asio/io_context.hpp>
#include <boost/asio/thread_pool.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <list>
#include <map>
#include <memory>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/http_types.hpp"
#include "cncstream/daemon/machines.hpp"
#include "cncstream/daemon/previews.hpp"
#include "cncstream/daemon/tool_store.hpp"
#include "cncstream/gcode/program_extent.hpp"
#include "cncstream/jobs/height_preview.hpp"
#include "cncstream/jobs/resume_job.hpp"
#include "cncstream/jobs/toolpath_job.hpp"
#include "cncstream/transport/journal.hpp"

namespace cncstream::daemon {

// A generated program, shared by every job with the same file and parameters.
struct Program {
  std::vector<std::string> lines;
  std::vector<long> source_lines;  // empty: 1..n
  std::int64_t total_lines = 0;
  std::string sha256;              // of the program text
  std::filesystem::path path;      // written under <data>/programs/ (the journal's `file`)
  std::optional<geometry::Mesh> work_mesh;   // STL jobs: the part in work coordinates (the simulator's verify)
  std::optional<cam::Cutter> cutter;
  std::map<int, cam::Cutter> tools;     // T number -> cutter, for a program of several tools
  std::optional<geometry::Box3> stock;       // the job's stock block (work coordinates)
  std::vector<jobs::OperationSummary> operations;  // STL jobs: roughing, finishing ...
  std::vector<std::string> notes;  // what the plan decided and why
  double seconds = 0;              // generation time
  gcode::ProgramExtent extent;     // for the travel check, traced off the event loop
  // The tool-tip heights for the preview (work coordinates): an STL
  // program's from its CL grid, set before the program is shared; a G-code
  // program's traced after `ready`, set on the event loop's thread (the only
  // thread that reads or writes it once the program is shared).
  mutable std::shared_ptr<const jobs::HeightPreview> height;
};

// When each file line's motion ends (s), for the ETA: computed after the
// program is ready (it traces the whole program), so it never delays a start.
struct EtaTable {
  std::vector<double> end_by_line;
  double estimated_s = 0;
};

// A shop job requeued on the machine it ran on (docs/shop.md, "Resume or
// restart"): queued as a resume after the hub's last reported line, planned
// as `cncstream resume` plans one once its program is ready.
struct ShopResume {
  std::int64_t after_line = 0;  // the hub's last reported line of the earlier run (> 0)
  std::int64_t ran_as = 0;      // that run's local job here (0: this daemon does not hold it)
};

struct DaemonJob {
  transport::DaemonJobRow row;
  nlohmann::json params;  // canonical (STL) or null (G-code)
  std::string cache_key;
  std::shared_ptr<const Program> program;
  std::shared_ptr<std::stop_source> stop;  // generation in progress
  std::string stage;
  double fraction = 0;
  bool cached = false;
  protocol::JobProgress progress;
  std::optional<SimVerifyReport> verify;
  std::optional<jobs::ResumePlan> resume;  // a confirmed resume: its lines
  std::optional<ShopResume> shop_resume;    // to plan once the program is ready (then `resume`)
  // The job's own tool-change settings over the machine's (its `tool_change`
  // object as given; null: the machine's). Not kept across a restart.
  nlohmann::json tool_change = nullptr;
};

class JobManager {
 public:
  JobManager(boost::asio::io_context& io, boost::asio::thread_pool& pool, const DaemonConfig& config, FileStore& files,
             Machines& machines, WsHub& hub, const std::filesystem::path& journal_path,
             const std::filesystem::path& programs_dir);
  ~JobManager();

  // After a restart: running/held -> interrupted (with the last answered
  // line), unfinished ones regenerated; nothing is started.
  void recover();
  // The jobs recover() found running and marked interrupted (the shop's
  // hub is told once it is joined: src/daemon/shop_link.cpp).
  const std::vector<std::int64_t>& interrupted_at_recovery() const { return interrupted_at_recovery_; }

  // throws ApiError; `shop_resume`: a shop job requeued on this machine,
  // which becomes ready only with its resume planned.
  nlohmann::json create(const nlohmann::json& body, std::optional<ShopResume> shop_resume = std::nullopt);
  nlohmann::json list(const std::optional<std::string>& machine, const std::optional<std::string>& state) const;
  DaemonJob& get(std::int64_t id);  // throws ApiError 404
  nlohmann::json to_json(const DaemonJob& j) const;
  std::shared_ptr<const Program> program(const DaemonJob& j) const { return j.program; }
  // The preview's height PNG and thinned path of a job's program (answer later).
  void preview_png(std::int64_t id, int max_px, Respond respond);
  void preview_path(std::int64_t id, std::size_t max_points, Respond respond);

  nlohmann::json start(std::int64_t id, const std::string& client);
  nlohmann::json generate(std::int64_t id);
  void hold(std::int64_t id);
  void resume(std::int64_t id, const std::string& client);
  void stop(std::int64_t id);
  nlohmann::json cancel(std::int64_t id, const std::string& client);
  // The shop's hub cancelled the shop job this one holds: cancelled unless it
  // has started (no control needed: it moves nothing); false when it had.
  bool cancel_for_shop(std::int64_t id);
  nlohmann::json move(std::int64_t id, std::int64_t position);
  // Answers later (plans on the pool).
  void resume_plan(std::int64_t id, long from_line, const std::string& client, const Respond& respond);
  nlohmann::json resume_confirm(std::int64_t id, const std::string& plan_id, const std::string& client);

  void stop_generations() {
    for (auto& [k, s] : generation_stop_) s->request_stop();
  }
  bool file_in_use(const std::string& file_id) const;
  nlohmann::json current_job(const std::string& machine) const;

  // Whether the machine has a job that has not ended (queued ... held).
  bool has_unfinished(const std::string& machine) const;
  // Told of every job's state change (the shop's outbox, src/daemon/shop_link.cpp).
  std::function<void(const DaemonJob&)> on_state_change;

  // Cache statistics (tests, benchmarks).
  std::size_t cache_size() const { return cache_.size(); }

 // The daemon's tool library (<data_dir>/tools.toml).
  ToolStore& tools() { return tools_; }

 private:
  void kick_generation(DaemonJob& j);
  // The program is there: ready, or (a shop resume) its resume planned first.
  void program_ready(DaemonJob& j);
  // What `cncstream resume` reads of a run: the program's lines and, when
  // `ran` ran this same program, its journal's last progress, planner depth,
  // earlier resume and refused lines.
  jobs::ResumeInput resume_input(const Program& p, const transport::DaemonJobRow& ran) const;
  using ResumePlanned = std::function<void(std::optional<jobs::ResumePlan> plan, const std::string& error)>;
  void plan_resume_async(jobs::ResumeInput in, ResumePlanned done);
  // The program cache's key: the file, the job's parameters and, for a part, the machine's link.
  std::string generation_key(const std::string& file_id, const nlohmann::json& params, const std::string& machine);
  void on_generated(const std::string& key, const std::shared_ptr<const Program>& p, const std::string& error,
                    bool cancelled);
  void persist(DaemonJob& j);
  void publish_job(const DaemonJob& j);
  void publish_queue(const std::string& machine);
  void set_state(DaemonJob& j, const std::string& state, const std::string& message = {});
  DaemonJob* running_on(const std::string& machine);
  // Machines::library_tool: the library's tool for T `number` of the job running on `machine`.
  nlohmann::json library_tool(const std::string& machine, int number) const;
  void cancel_waiting(DaemonJob& j, const std::string& message);
  std::vector<DaemonJob*> unfinished(const std::string& machine);
  Machine& machine_of(const DaemonJob& j);
  void cache_put(const std::string& key, std::shared_ptr<const Program> p);
  void on_started(const std::string& machine, std::int64_t journal_id);
  void on_progress(const std::string& machine, const protocol::JobProgress& p);
  void on_state(const std::string& machine, const std::string& state);
  void on_holding(const std::string& machine, bool holds, long last_answered_line);
  void on_ended(const std::string& machine, protocol::JobOutcome o, long last_line, const std::string& text);
  void on_verified(const std::string& machine, SimVerifyReport rep);
  void on_start_failed(const std::string& machine, const std::string& why);
  double fraction(const DaemonJob& j) const;
  std::optional<double> eta(const DaemonJob& j) const;
  const EtaTable* eta_table(const DaemonJob& j) const;
  std::shared_ptr<const Program> program_for_preview(std::int64_t id);

  boost::asio::io_context& io_;
  boost::asio::thread_pool& pool_;
  const DaemonConfig& config_;
  FileStore& files_;
  Machines& machines_;
  WsHub& hub_;
  std::filesystem::path programs_dir_;
  transport::Journal journal_;
  ToolStore tools_;
  std::map<std::int64_t, std::unique_ptr<DaemonJob>> jobs_;
  std::map<std::string, std::int64_t> running_;   // machine -> job
  std::map<std::string, std::int64_t> last_run_;  // machine -> the last job started there (its verify report)
  // The cache: key -> program, least recently used first.
  std::list<std::pair<std::string, std::shared_ptr<const Program>>> cache_;
  std::map<std::string, std::shared_ptr<const EtaTable>> etas_;  // by program SHA-256
  std::map<std::string, std::vector<std::int64_t>> generating_;  // key -> jobs waiting for it
  std::map<std::string, std::shared_ptr<std::stop_source>> generation_stop_;
  struct PendingPlan {
    std::int64_t job;
    std::string client;
    jobs::ResumePlan plan;
    double expires;
  };
  std::map<std::string, PendingPlan> plans_;
  std::vector<std::int64_t> interrupted_at_recovery_;
  Previews previews_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace cncstream::daemon
