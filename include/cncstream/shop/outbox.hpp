#pragma once
// The outbox: events for the hub, written first to the daemon's own SQLite
// journal (tables shop_outbox and shop_jobs in the same file), numbered per
// machine 1, 2, 3 ... A shipper sends the unsent ones in order and marks
// them sent only after the hub committed them, so a hub that was down, a
// PC that was offline or a daemon killed mid-send replays without gaps, and
// the hub's ON CONFLICT DO NOTHING drops what arrives twice. Thread-safe.
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "cncstream/shop/hub.hpp"

struct sqlite3;

namespace cncstream::shop {

class Outbox {
 public:
  explicit Outbox(const std::filesystem::path& journal);  // throws ShopError naming the file
  ~Outbox();
  Outbox(const Outbox&) = delete;
  Outbox& operator=(const Outbox&) = delete;

  // Appends (committed, fsynced) and returns the machine's sequence number.
  std::int64_t append(const std::string& machine, const std::string& kind, std::int64_t shop_job,
                      const std::string& body_json);
  // The oldest unsent events of one machine, in order.
  std::vector<OutboxEvent> unsent(const std::string& machine, int limit) const;
  // Machines with unsent events.
  std::vector<std::string> machines_with_unsent() const;
  void mark_sent(const std::string& machine, std::int64_t up_to_seq);
  std::int64_t unsent_count() const;

  // For another consumer of the same events (MQTT): those after `seq`, sent
  // to the hub or not, and where that consumer has got to.
  std::vector<OutboxEvent> after(const std::string& machine, std::int64_t seq, int limit) const;
  std::int64_t cursor(const std::string& consumer, const std::string& machine) const;
  void set_cursor(const std::string& consumer, const std::string& machine, std::int64_t seq);

  // Which local (daemon) job runs which shop job.
  void link_job(std::int64_t local_id, std::int64_t shop_id, const std::string& machine);
  std::optional<std::int64_t> shop_job_of(std::int64_t local_id) const;
  // The newest local job that holds the shop job, if any.
  std::optional<std::int64_t> local_job_of(std::int64_t shop_id) const;

 private:
  void exec(const char* sql) const;
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
  mutable std::mutex mu_;
};

}  // namespace cncstream::shop
