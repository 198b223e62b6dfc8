#include "cncstream/protocol/identifier.hpp"

#include <fmt/core.h>

#include <limits>

#include <algorithm>
#include <stdexcept>

#include "cncstream/protocol/pattern.hpp"
#include "cncstream/protocol/response.hpp"

namespace cncstream::protocol {

namespace {

bool matches_any(const std::vector<std::string>& patterns, std::string_view line) {
  return matches_any_pattern(patterns, line);
}

const FirmwareProfile* find_id(const std::vector<FirmwareProfile>& ps, const std::string& id) {
  for (const auto& p : ps)
    if (p.id == id) return &p;
  return nullptr;
}

}  // namespace

FirmwareIdentifier::FirmwareIdentifier(std::vector<FirmwareProfile> profiles, IdentifyOptions opt)
    : profiles_(std::move(profiles)), opt_(opt) {
  if (!find_id(profiles_, "grbl-1.1"))
    throw std::invalid_argument("firmware identification needs the grbl-1.1 profile (the fallback's base)");
  std::stable_sort(profiles_.begin(), profiles_.end(), [](const auto& a, const auto& b) { return a.priority > b.priority; });
}

const FirmwareProfile* FirmwareIdentifier::match_banner(const std::vector<FirmwareProfile>& profiles,
                                                        std::string_view line) {
  const FirmwareProfile* best = nullptr;
  for (const auto& p : profiles)
    if (matches_any(p.banner_patterns, line) && (!best || p.priority > best->priority)) best = &p;
  return best;
}

void FirmwareIdentifier::start(double now) {
  phase_ = Phase::WaitBanner;
  deadline_ = now + opt_.banner_timeout_s;
}

void FirmwareIdentifier::send_query(const std::string& query, double now) {
  output_ += query + "\n";
  lines_.clear();
  phase_ = Phase::Query;
  deadline_ = now + opt_.query_timeout_s;
}

void FirmwareIdentifier::poll_status(double now) {
  output_ += "?";
  next_poll_ = now + opt_.status_poll_s;
}

void FirmwareIdentifier::on_line(std::string_view line, double now) {
  if (phase_ == Phase::Idle || phase_ == Phase::Done) return;
  if (phase_ == Phase::WaitQuiet && !match_banner(profiles_, line)) {
    const auto r = parse_response(line);
    if (r.kind == ResponseKind::Status && r.status) {
      status_seen_ = true;
      const auto st = r.status->state;
      if (st == MachineState::Idle || st == MachineState::Alarm) {
        if (++calm_reports_ >= 2) send_query("$I", now);
      } else {
        calm_reports_ = 0;
        if (!busy_noted_) {
          busy_noted_ = true;
          notes_.push_back("the controller is busy (" + r.status->state_text +
                           ") with lines sent before this connection (a program that died mid-job?): waiting for it "
                           "to finish before identifying it; a held machine waits for cycle start or a reset");
        }
      }
    } else if (r.kind == ResponseKind::Ok || r.kind == ResponseKind::Error) {
      calm_reports_ = 0;  // an answer to an earlier host's line: not ours, and it was not quiet
    }
    return;
  }
  if (const auto* p = match_banner(profiles_, line)) {
    // A banner during the query means the board was still booting: ask again.
    candidate_ = p;
    banner_ = std::string(line);
    send_query(p->identify_query.empty() ? "$I" : p->identify_query, now);
    return;
  }
  if (phase_ != Phase::Query) return;  // boot noise before the banner
  const auto r = parse_response(line);
  if (r.kind == ResponseKind::Status) return;  // a late answer to a '?' of the wait
  if (r.kind == ResponseKind::Ok) {
    // Every query's answer has lines before its ok: a lone ok answers
    // something else (an earlier host's line).
    if (lines_.empty()) {
      lone_ok_ = true;
      return;
    }
    finish(nullptr);
  } else if (r.kind == ResponseKind::Error || r.kind == ResponseKind::Alarm) {
    // Some controllers refuse $I in alarm or answer ALARM first; keep what we have.
    lines_.emplace_back(line);
    if (r.kind == ResponseKind::Error) finish(nullptr);
  } else {
    lines_.emplace_back(line);
  }
}

double FirmwareIdentifier::next_deadline() const {
  if (phase_ == Phase::WaitQuiet) return status_seen_ ? next_poll_ : std::min(next_poll_, deadline_);
  if (phase_ == Phase::WaitBanner || phase_ == Phase::Query) return deadline_;
  return std::numeric_limits<double>::infinity();
}

void FirmwareIdentifier::tick(double now) {
  if (phase_ == Phase::WaitBanner && now >= deadline_) {
    warnings_.push_back(fmt::format("no banner within {:.1f}", opt_.banner_timeout_s) +
                        " s after opening the port (board without DTR reset?); asking with $I once it is idle");
    phase_ = Phase::WaitQuiet;
    deadline_ = now + opt_.query_timeout_s;
    poll_status(now);
  } else if (phase_ == Phase::WaitQuiet) {
    if (!status_seen_ && now >= deadline_) {
      send_query("$I", now);  // no answer to '?': ask as before
    } else if (now >= next_poll_) {
      poll_status(now);
    }
  } else if (phase_ == Phase::Query && now >= deadline_) {
    finish(lone_ok_ ? "the identification query got a bare 'ok' and no version" : "no answer to the identification query");
  }
}

void FirmwareIdentifier::finish(const char* why) {
  if (why) warnings_.emplace_back(why);
  const FirmwareProfile* chosen = nullptr;
  for (const auto& p : profiles_) {
    for (const auto& l : lines_)
      if (matches_any(p.version_patterns, l)) {
        chosen = &p;
        break;
      }
    if (chosen) break;
  }
  Identification id;
  // A more specific banner (higher priority) beats a generic version line:
  // grblHAL answers [VER:1.1f...] like GRBL 1.1 does.
  if (candidate_ && (!chosen || candidate_->priority > chosen->priority)) chosen = candidate_;
  if (chosen) {
    id.profile = *chosen;
    id.recognised = true;
  } else {
    id.profile = conservative_grbl_subset(*find_id(profiles_, "grbl-1.1"));
    warnings_.push_back("controller not recognised (banner '" + banner_ +
                        "'); using the conservative GRBL 1.1 subset: 128-byte buffer, 80-character lines, "
                        "no extended real-time bytes");
  }
  // [OPT:flags,blocks,rx] reports the real sizes; trust it over the profile.
  for (const auto& l : lines_) {
    const auto r = parse_response(l);
    if (r.kind != ResponseKind::Options || id.profile.flow != FlowControl::CharacterCounting) continue;
    if (const auto o = parse_build_options(r.body)) {
      if (o->planner_blocks) id.profile.planner_blocks = *o->planner_blocks;
      if (o->rx_buffer_size) {
        if (static_cast<std::size_t>(*o->rx_buffer_size) <= id.profile.rx_margin)
          warnings_.push_back("ignoring implausible RX size in '" + l + "'");
        else
          id.profile.rx_buffer_size = static_cast<std::size_t>(*o->rx_buffer_size);
      }
    } else {
      warnings_.push_back("cannot read build options '" + l + "'");
    }
  }
  id.banner = banner_;
  id.query_lines = lines_;
  id.warnings = warnings_;
  result_ = std::move(id);
  phase_ = Phase::Done;
}

}  // namespace cncstream::protocol
