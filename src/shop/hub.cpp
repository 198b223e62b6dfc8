#include "cncstream/shop/hub.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace cncstream::shop {

std::string pg_text_array(const std::vector<std::string>& items) {
  std::string out = "{";
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i) out.push_back(',');
    out.push_back('"');
    for (char c : items[i]) {
      if (c == '"' || c == '\\') out.push_back('\\');
      out.push_back(c);
    }
    out.push_back('"');
  }
  out.push_back('}');
  return out;
}

std::vector<HubJobStatus> Hub::heartbeat(const MachineInfo& m, const MachineState& s, double lease_s) {
  nlohmann::json info = {{"profile", m.profile}, {"capabilities", m.capabilities}};
  if (m.travel_mm) info["travel_mm"] = *m.travel_mm;
  const auto r = db_.exec("SELECT shop.heartbeat($1, $2, $3::jsonb, $4::jsonb, $5)",
                          {m.name, m.pc, info.dump(), s.to_json(), fmt::format("{}", lease_s)});
  std::vector<HubJobStatus> out;
  const auto j = nlohmann::json::parse(r.text(0, 0));
  for (const auto& e : j.at("jobs")) out.push_back({e.at("id").get<std::int64_t>(), e.at("status").get<std::string>()});
  return out;
}

std::optional<ClaimedJob> Hub::claim_job(const std::string& machine, double lease_s) {
  const auto r = db_.exec("SELECT id, file_name, kind, content, params, resume_after_line FROM shop.claim_job($1, $2)",
                          {machine, fmt::format("{}", lease_s)});
  if (r.rows() == 0) return std::nullopt;
  ClaimedJob j;
  j.id = r.i64(0, 0);
  j.file_name = r.text(0, 1);
  j.kind = r.text(0, 2);
  j.content = bytes_from_bytea_hex(r.text(0, 3));
  j.params_json = r.text(0, 4);
  j.resume_after_line = r.i64(0, 5);
  return j;
}

std::int64_t Hub::report_events(const std::string& machine, const std::vector<OutboxEvent>& events) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& e : events) {
    nlohmann::json body;
    try {
      body = nlohmann::json::parse(e.body_json.empty() ? "{}" : e.body_json);
    } catch (const nlohmann::json::exception&) {
      body = {{"text", e.body_json}};  // kept, never blocks the outbox
    }
    arr.push_back({{"seq", e.seq}, {"at", e.at}, {"kind", e.kind},
                   {"job", e.shop_job ? nlohmann::json(e.shop_job) : nlohmann::json(nullptr)}, {"body", body}});
  }
  return db_.exec("SELECT shop.report_events($1, $2::jsonb)", {machine, arr.dump()}).i64(0, 0);
}

std::int64_t Hub::submit_job(const Submission& s) {
  PgParams p = {s.file_name, s.kind, bytea_hex(s.content),
                s.params_json.empty() ? std::nullopt : std::optional<std::string>(s.params_json),
                pg_text_array(s.needs), s.machine.empty() ? std::nullopt : std::optional<std::string>(s.machine)};
  return db_.exec("SELECT shop.submit_job($1, $2, $3::bytea, $4::jsonb, $5::text[], $6)", p).i64(0, 0);
}

void Hub::cancel_job(std::int64_t id) { db_.exec("SELECT shop.cancel_job($1)", {std::to_string(id)}); }

void Hub::ping() { db_.exec("SELECT 1"); }

void Hub::requeue_job(std::int64_t id, bool same_machine) {
  db_.exec("SELECT shop.requeue_job($1, $2)", {std::to_string(id), same_machine ? "true" : "false"});
}

}  // namespace cncstream::shop
