// `cncstream shop init URL`: creates or migrates the shop hub's schema;
// `cncstream shop jobs URL`: the shop's queue and history;
// `cncstream shop requeue URL ID [--anywhere]`: an interrupted job back into the
// queue, as a resume on the machine it ran on or a restart anywhere;
// `cncstream submit PART.stl|PART.nc --shop URL [--machine NAME | --needs TAG...]`:
// a job for the shop's queue (docs/shop.md).
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cncstream/shop/hub.hpp"
#include "cncstream/shop/schema.hpp"
#include "commands.hpp"

namespace cncstream::app {

namespace {

std::string read_part(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string kind_of(const std::string& path) {
  auto lower = path;
  for (auto& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.ends_with(".stl")) return "stl";
  for (const char* ext : {".nc", ".gcode", ".ngc", ".tap", ".gc", ".g"})
    if (lower.ends_with(ext)) return "gcode";
  throw std::runtime_error(path + ": neither an STL (.stl) nor a G-code program (.nc, .gcode, .ngc, .tap)");
}

}  // namespace

void register_shop(CLI::App& app, CommandRegistry& registry) {
  auto* shop = app.add_subcommand("shop", "The shop's hub (PostgreSQL): init, jobs, requeue (docs/shop.md)");
  shop->require_subcommand(1, 1);

  auto url = std::make_shared<std::string>();
  auto* init = shop->add_subcommand("init", "Create or migrate the hub's schema, roles and functions");
  init->add_option("URL", *url, "postgresql://ADMIN@HOST/DB")->required();
  registry.add(init, [url] {
    shop::PgConnection db(*url);
    const auto r = shop::migrate(db);
    if (r.from == r.to) std::cout << "shop hub " << shop::redact_url(*url) << ": schema version " << r.to << ", up to date\n";
    else std::cout << "shop hub " << shop::redact_url(*url) << ": schema version " << r.from << " -> " << r.to << "\n";
    return 0;
  });

  auto list_url = std::make_shared<std::string>();
  auto limit = std::make_shared<int>(50);
  auto* jobs = shop->add_subcommand("jobs", "The shop's jobs, newest first");
  jobs->add_option("URL", *list_url, "postgresql://USER@HOST/DB (a role that may read: cncstream_operator/reader)")->required();
  jobs->add_option("-n,--limit", *limit, "How many")->check(CLI::Range(1, 100000));
  registry.add(jobs, [list_url, limit] {
    shop::PgConnection db(*list_url);
    const auto r = db.exec(
        "SELECT j.id, j.status, coalesce(m.name, j.machine, '-'), j.file_name, j.last_line, j.message"
        " FROM shop.jobs j LEFT JOIN shop.machines m ON m.id = j.machine_id ORDER BY j.id DESC LIMIT $1",
        {std::to_string(*limit)});
    for (int i = 0; i < r.rows(); ++i) {
      std::cout << std::setw(6) << r.i64(i, 0) << "  " << std::setw(17) << std::left << r.text(i, 1) << std::right << "  "
                << std::setw(12) << std::left << r.text(i, 2) << std::right << "  " << r.text(i, 3);
      if (r.i64(i, 4)) std::cout << "  line " << r.i64(i, 4);
      if (!r.text(i, 5).empty()) std::cout << "  (" << r.text(i, 5) << ")";
      std::cout << "\n";
    }
    return 0;
  });

  struct Requeue {
    std::string url;
    long long id = 0;
    bool anywhere = false;
  };
  auto rq = std::make_shared<Requeue>();
  auto* requeue = shop->add_subcommand("requeue", "Put an interrupted, failed or cancelled job back into the queue");
  requeue->add_option("URL", rq->url, "postgresql://OPERATOR@HOST/DB")->required();
  requeue->add_option("JOB", rq->id, "The shop's job id")->required();
  requeue->add_flag("--anywhere", rq->anywhere,
                    "A restart from the top on any machine that can do it (default: a resume on the machine it ran "
                    "on, after the last line it reported)");
  registry.add(requeue, [rq] {
    shop::PgConnection db(rq->url);
    shop::Hub(db).requeue_job(rq->id, !rq->anywhere);
    std::cout << "job " << rq->id << " is pending again";
    if (rq->anywhere) {
      std::cout << ": a restart from the top on any machine that can do it\n";
    } else {
      std::string where = " on the machine it ran on";
      try {  // an operator's login reads the tables; a web operator's does not
        const auto r = db.exec("SELECT m.name, j.resume_after_line FROM shop.jobs j"
                               " LEFT JOIN shop.machines m ON m.id = j.resume_machine_id WHERE j.id = $1",
                               {std::to_string(rq->id)});
        if (r.rows() && r.is_null(0, 1))
          where = std::string(": on ").append(r.text(0, 0)).append(", from the top (no line was reported)");
        else if (r.rows())
          where = std::string(": a resume on ").append(r.text(0, 0)).append(" after line ").append(r.text(0, 1));
      } catch (const shop::ShopError&) {
      }
      std::cout << where << " (its operator starts it there)\n";
    }
    return 0;
  });

  struct Submit {
    std::string file, url, machine, params, tool;
    std::vector<std::string> needs;
  };
  auto s = std::make_shared<Submit>();
  auto* submit = app.add_subcommand("submit", "Put a part or program into the shop's queue (docs/shop.md)");
  submit->add_option("FILE", s->file, "PART.stl or PROGRAM.nc")->required();
  submit->add_option("--shop", s->url, "The hub: postgresql://OPERATOR@HOST/DB")->required();
  auto* machine = submit->add_option("--machine", s->machine, "Only this machine");
  submit->add_option("--needs", s->needs, "Capabilities the machine must have (tags its daemon declares)")
      ->excludes(machine);
  submit->add_option("--params", s->params, "An STL's tool path parameters as JSON (the daemon API's, docs/api-v1.md)");
  submit->add_option("--tool", s->tool, "An STL's cutter (e.g. ball:3.175), when --params has none");
  registry.add(submit, [s] {
    shop::Submission sub;
    sub.kind = kind_of(s->file);
    sub.file_name = std::filesystem::path(s->file).filename().string();
    sub.content = read_part(s->file);
    sub.machine = s->machine;
    sub.needs = s->needs;
    if (sub.kind == "stl") {
      nlohmann::json p = nlohmann::json::object();
      if (!s->params.empty()) {
        try {
          p = nlohmann::json::parse(s->params);
        } catch (const nlohmann::json::exception& e) {
          throw std::runtime_error(std::string("--params: not JSON: ") + e.what());
        }
        if (!p.is_object()) throw std::runtime_error("--params: expected a JSON object");
      }
      if (!s->tool.empty()) p["tool"] = s->tool;
      if (!p.contains("tool")) throw std::runtime_error("an STL needs its cutter: --tool SPEC or \"tool\" in --params");
      sub.params_json = p.dump();
    } else if (!s->params.empty() || !s->tool.empty()) {
      throw std::runtime_error("--params and --tool are for an STL; a program runs as it is");
    }
    shop::PgConnection db(s->url);
    const auto id = shop::Hub(db).submit_job(sub);
    std::cout << "shop job " << id << ": " << sub.file_name << " is pending"
              << (sub.machine.empty() ? std::string() : " for machine " + sub.machine) << "\n";
    return 0;
  });
}

}  // namespace cncstream::app
