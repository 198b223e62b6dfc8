#pragma once
// The hub's functions as C++ calls: what a PC calls (heartbeat, claim_job,
// report_events, under the role cncstream_pc) and what an operator calls
// (submit_job, cancel_job, requeue_job, under cncstream_operator).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/shop/machine_state.hpp"
#include "cncstream/shop/pg.hpp"

namespace cncstream::shop {

// What a machine is, for the shop's matching.
struct MachineInfo {
  std::string name;
  std::string pc;
  std::string profile;
  std::optional<std::array<double, 3>> travel_mm;
  std::vector<std::string> capabilities;
};

struct ClaimedJob {
  std::int64_t id = 0;
  std::string file_name;
  std::string kind;     // "stl" | "gcode"
  std::string content;  // the file's bytes
  std::string params_json;  // "" : none
  // Requeued on the machine it ran on (migration 5): resume after this
  // 1-based line, its last reported one (0: from the top).
  std::int64_t resume_after_line = 0;
};

// One journal event on its way to the hub.
struct OutboxEvent {
  std::int64_t seq = 0;  // the machine's own numbering, 1, 2, ...
  std::string at;        // ISO 8601 UTC
  std::string kind;      // "job", "progress", "state"
  std::int64_t shop_job = 0;  // 0: none
  std::string body_json;
};

struct HubJobStatus {
  std::int64_t id = 0;
  std::string status;
};

struct Submission {
  std::string file_name;
  std::string kind;
  std::string content;
  std::string params_json;  // "" : none
  std::vector<std::string> needs;
  std::string machine;  // "" : any that can
};

class Hub {
 public:
  explicit Hub(PgConnection& db) : db_(db) {}
  // Registers or updates the machine, stores its state, renews its jobs'
  // leases; returns its live jobs' statuses.
  std::vector<HubJobStatus> heartbeat(const MachineInfo& m, const MachineState& s, double lease_s);
  std::optional<ClaimedJob> claim_job(const std::string& machine, double lease_s);
  // Returns the highest sequence the hub holds for the machine.
  std::int64_t report_events(const std::string& machine, const std::vector<OutboxEvent>& events);

  std::int64_t submit_job(const Submission& s);
  void cancel_job(std::int64_t id);
  void requeue_job(std::int64_t id, bool same_machine);
  // Asks the hub for nothing (SELECT 1): whether it still answers.
  void ping();

 private:
  PgConnection& db_;
};

// A PostgreSQL text[] literal ({"a","b"}) with quotes and backslashes escaped.
std::string pg_text_array(const std::vector<std::string>& items);

}  // namespace cncstream::shop
