#include "cncstream/daemon/previews.hpp"

#include <boost/asio/post.hpp>
#include <spdlog/spdlog.h>

#include <cmath>

#include "cncstream/daemon/job_manager.hpp"
#include "cncstream/gcode/program.hpp"
#include "cncstream/image/image.hpp"
#include "cncstream/jobs/height_preview.hpp"
#include "cncstream/jobs/path_preview.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {

// Where nothing was cut: the page's dark canvas, so the part stands out.
constexpr image::Rgb kNoData{11, 13, 16};

gcode::ProgramTrace trace_of(const Program& p) {
  std::string text;
  std::size_t size = 0;
  for (const auto& l : p.lines) size += l.size() + 1;
  text.reserve(size);
  for (const auto& l : p.lines) {
    text.append(l);
    text.push_back('\n');
  }
  return gcode::trace_program(text);
}

// Millimetres to the micron: the drawing needs no more, the JSON stays small.
double micron(double v) { return std::round(v * 1000) / 1000; }

json flat(const std::vector<std::vector<geometry::Vec3>>& lines) {
  json out = json::array();
  for (const auto& l : lines) {
    json a = json::array();
    for (const auto& p : l) {
      a.push_back(micron(p.x));
      a.push_back(micron(p.y));
      a.push_back(micron(p.z));
    }
    out.push_back(std::move(a));
  }
  return out;
}

std::shared_ptr<const jobs::HeightPreview> traced_heights(const Program& p) {
  return std::make_shared<const jobs::HeightPreview>(jobs::height_preview_from_trace(trace_of(p)));
}

}  // namespace

Previews::Bytes Previews::Lru::get(const std::string& key) {
  for (auto it = items.begin(); it != items.end(); ++it)
    if (it->first == key) {
      items.splice(items.end(), items, it);
      return items.back().second;
    }
  return nullptr;
}

void Previews::Lru::put(const std::string& key, Bytes value) {
  items.remove_if([&](const auto& e) { return e.first == key; });
  items.emplace_back(key, std::move(value));
  while (items.size() > capacity) items.pop_front();
}

Previews::Previews(boost::asio::io_context& io, boost::asio::thread_pool& pool) : io_(io), pool_(pool) {}

Previews::~Previews() { *alive_ = false; }

void Previews::serve(Lru& cache, const std::string& key, const std::string& content_type, Respond respond,
                     std::function<Response()> make) {
  if (auto hit = cache.get(key)) {
    Response r;
    r.content_type = content_type;
    r.body = *hit;
    respond(std::move(r));
    return;
  }
  auto& waiting = waiting_[key];
  waiting.push_back(std::move(respond));
  if (waiting.size() > 1) return;  // being made for an earlier request
  boost::asio::post(pool_, [this, &cache, key, content_type, make = std::move(make), alive = alive_] {
    Response r;
    try {
      r = make();
      if (r.status == 200) r.content_type = content_type;
    } catch (const std::exception& e) {
      r = Response::error(500, "internal", e.what());
    }
    boost::asio::post(io_, [this, &cache, key, r = std::move(r), alive] {
      if (!*alive) return;
      if (r.status == 200) cache.put(key, std::make_shared<const std::string>(r.body));
      auto list = std::move(waiting_[key]);
      waiting_.erase(key);
      for (auto& respond : list) respond(r);
    });
  });
}

void Previews::png(const std::shared_ptr<const Program>& program, int max_px, Respond respond) {
  std::string key = "png:";
  key.append(program->sha256).append(":").append(std::to_string(max_px));
  // Read here: only the event loop's thread touches a shared program's height.
  auto height = program->height;
  serve(pngs_, key, "image/png", std::move(respond), [this, program, height, max_px, alive = alive_] {
    auto h = height;
    if (!h) {  // not traced yet (or the trace after `ready` is still running)
      h = traced_heights(*program);
      boost::asio::post(io_, [program, h, alive] {
        if (*alive && !program->height) program->height = h;
      });
    }
    if (h->empty()) return Response::error(404, "not_found", "the program has no cutting move: no height image");
    Response r;
    r.body = image::encode_png(jobs::render_height_preview(*h, max_px, kNoData));
    return r;
  });
}

void Previews::path(const std::shared_ptr<const Program>& program, std::size_t max_points, Respond respond) {
  std::string key = "path:";
  key.append(program->sha256).append(":").append(std::to_string(max_points));
  serve(paths_, key, "application/json", std::move(respond), [program, max_points] {
    const auto p = jobs::decimate_path(trace_of(*program), max_points);
    return Response::json(200, {{"points", p.points},
                                {"total_points", p.total_points},
                                {"cuts", flat(p.cuts)},
                                {"rapids", flat(p.rapids)}});
  });
}

}  // namespace cncstream::daemon
