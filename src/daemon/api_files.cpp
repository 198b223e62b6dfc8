// Files: upload (spooled to disk by the server, hashed and classified on the
// worker pool), list, get, download, delete.
#include <boost/asio/post.hpp>

#include "cncstream/daemon/api.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace {
json file_json(const FileInfo& f) {
  json j = {{"id", f.id}, {"name", f.name}, {"kind", f.kind}, {"size", f.size}, {"uploaded_at", f.uploaded_at}};
  if (f.kind == "stl") j["facets"] = f.facets;
  else j["lines"] = f.lines;
  return j;
}
}  // namespace

void Api::file_routes() {
  router_.add("POST", "/api/v1/files", [this](Request& r, const Respond& res) {
    if (r.body_file.empty()) throw ApiError{400, "bad_request", "empty upload"};
    const std::string label = r.query_value("name").value_or("unnamed");
    boost::asio::post(pool_, [this, temp = r.body_file, label, res] {
      try {
        auto [info, created] = files_.ingest(temp, label);
        res(Response::json(created ? 201 : 200, file_json(info)));
      } catch (const FileStoreError& e) {
        res(Response::error(e.status, e.code, e.what()));
      } catch (const std::exception& e) {
        std::error_code ec;
        std::filesystem::remove(temp, ec);
        res(Response::error(500, "internal", e.what()));
      }
    });
  });
  router_.add("GET", "/api/v1/files", [this](Request&, const Respond& res) {
    json list = json::array();
    for (const auto& f : files_.list()) list.push_back(file_json(f));
    res(Response::json(200, {{"files", list}}));
  });
  router_.add("GET", "/api/v1/files/{id}", [this](Request& r, const Respond& res) {
    const auto f = files_.get(r.params.at(0));
    if (!f) throw ApiError{404, "not_found", "no file '" + r.params.at(0).substr(0, 64) + "'"};
    res(Response::json(200, file_json(*f)));
  });
  // The bytes as uploaded (the viewer shows an STL job's part from them).
  router_.add("GET", "/api/v1/files/{id}/content", [this](Request& r, const Respond& res) {
    const auto f = files_.get(r.params.at(0));
    const auto path = f ? files_.content_path(f->id) : std::nullopt;
    if (!path) throw ApiError{404, "not_found", "no file '" + r.params.at(0).substr(0, 64) + "'"};
    Response resp;
    resp.content_type = f->kind == "stl" ? "model/stl" : "text/plain; charset=us-ascii";
    resp.file = *path;
    res(std::move(resp));
  });
  router_.add("DELETE", "/api/v1/files/{id}", [this](Request& r, const Respond& res) {
    const std::string& id = r.params.at(0);
    if (!files_.get(id)) throw ApiError{404, "not_found", "no file '" + id.substr(0, 64) + "'"};
    if (jobs_.file_in_use(id)) throw ApiError{409, "bad_state", "a queued or running job uses this file"};
    files_.remove(id);
    Response resp;
    resp.status = 204;
    res(std::move(resp));
  });
}

}  // namespace cncstream::daemon
