// The tool library over the API: list, get, create, replace, delete and
// import (GET/POST /api/v1/tools, GET/PUT/DELETE /api/v1/tools/{number},
// POST /api/v1/tools/import). The library is the daemon's own
// (<data_dir>/tools.toml); each change is saved before it is answered.
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <cmath>
#include <fstream>

#include "cncstream/daemon/api.hpp"
#include "cncstream/daemon/json_body.hpp"
#include "cncstream/tooling/tool_import.hpp"

namespace cncstream::daemon {

using nlohmann::json;

namespace detail_api_tools {

json tool_json(const tooling::Tool& t) {
  json cutting = json::array();
  for (const auto& c : t.cutting) {
    json d = {{"material", c.material}};
    tooling::for_each_value(c, [&](const char* key, const std::optional<double>& v) { d[key] = v ? json(*v) : json(nullptr); });
    cutting.push_back(d);
  }
  return {{"number", t.number},
          {"name", t.name},
          {"shape", t.geometry.spec()},
          {"description", t.geometry.description()},
          {"flutes", t.flutes},
          {"flute_length", t.flute_length},
          {"overall_length", t.overall_length},
          {"stick_out", t.stick_out},
          {"shank_diameter", t.shank_diameter},
          {"length_offset", t.length_offset},
          {"notes", t.notes},
          {"cutting", cutting}};
}

[[noreturn]] void bad(const std::string& what) { throw ApiError{400, "bad_request", what}; }

double number(const json& b, const char* key, double dflt) {
  if (!b.contains(key) || b.at(key).is_null()) return dflt;
  if (!b.at(key).is_number()) bad(std::string(key) + ": expected a number");
  return b.at(key).get<double>();
}

std::string text(const json& b, const char* key, std::size_t max) {
  if (!b.contains(key) || b.at(key).is_null()) return {};
  if (!b.at(key).is_string()) bad(std::string(key) + ": expected a string");
  std::string s = b.at(key).get<std::string>();
  if (s.size() > max) bad(std::string(key) + ": too long");
  return s;
}

tooling::Tool tool_from(const json& b, int tool_no) {
  if (!b.is_object()) bad("expected a tool object");
  tooling::Tool t;
  t.number = tool_no;
  t.name = text(b, "name", 80);
  const std::string shape = text(b, "shape", 64);
  if (shape.empty()) bad("shape: required, a spec such as ball:3.175 or taper:1:5:3.175");
  try {
    t.geometry = tooling::parse_tool_spec(shape);
  } catch (const std::invalid_argument& e) {
    bad(std::string("shape: ") + e.what());
  }
  const double flutes = number(b, "flutes", 2);
  if (flutes != std::floor(flutes)) bad("flutes: expected a whole number");
  t.flutes = static_cast<int>(flutes);
  t.flute_length = number(b, "flute_length", 0);
  t.overall_length = number(b, "overall_length", 0);
  t.stick_out = number(b, "stick_out", 0);
  t.shank_diameter = number(b, "shank_diameter", 0);
  t.length_offset = number(b, "length_offset", 0);
  t.notes = text(b, "notes", 500);
  if (b.contains("cutting") && !b.at("cutting").is_null()) {
    if (!b.at("cutting").is_array() || b.at("cutting").size() > 64) bad("cutting: expected an array of cutting data");
    for (const auto& c : b.at("cutting")) {
      if (!c.is_object()) bad("cutting: expected objects");
      tooling::CuttingData d;
      d.material = text(c, "material", 64);
      tooling::for_each_value(d, [&](const char* key, std::optional<double>& v) {
        if (c.contains(key) && !c.at(key).is_null()) v = number(c, key, 0);
      });
      t.cutting.push_back(d);
    }
  }
  try {
    tooling::check_tool(t);
  } catch (const std::invalid_argument& e) {
    bad(e.what());
  }
  return t;
}

int tool_number(const std::string& s) {
  int n = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), n);
  if (ec != std::errc() || p != s.data() + s.size() || n < 1 || n > 9999)
    throw ApiError{404, "not_found", "no tool '" + s.substr(0, 16) + "' (tools are numbered 1..9999)"};
  return n;
}

}  // namespace detail_api_tools

void Api::tool_routes() {
  using namespace detail_api_tools;
  router_.add("GET", "/api/v1/tools", [this](Request&, const Respond& res) {
    json list = json::array();
    for (const auto& t : jobs_.tools().snapshot().tools) list.push_back(tool_json(t));
    res(Response::json(200, {{"tools", list}}));
  });
  router_.add("GET", "/api/v1/tools/{number}", [this](Request& r, const Respond& res) {
    const int n = tool_number(r.params.at(0));
    const auto lib = jobs_.tools().snapshot();
    const tooling::Tool* t = lib.by_number(n);
    if (!t) throw ApiError{404, "not_found", "no tool " + std::to_string(n)};
    res(Response::json(200, tool_json(*t)));
  });
  router_.add("POST", "/api/v1/tools", [this](Request& r, const Respond& res) {
    const json b = parse_body(r);
    const double n = number(b, "number", 0);
    if (n != std::floor(n) || n < 0 || n > 9999) bad("number: expected a whole number 1..9999");
    const int number_or_free = n > 0 ? static_cast<int>(n) : jobs_.tools().snapshot().free_number();
    const tooling::Tool t = tool_from(b, number_or_free);
    if (jobs_.tools().snapshot().by_number(t.number))
      throw ApiError{409, "conflict", "tool number " + std::to_string(t.number) + " is taken: PUT /api/v1/tools/" +
                                          std::to_string(t.number) + " replaces it"};
    try {
      jobs_.tools().put(t, false);
    } catch (const std::invalid_argument& e) {
      throw ApiError{409, "conflict", e.what()};
    }
    res(Response::json(201, tool_json(t)));
  });
  router_.add("PUT", "/api/v1/tools/{number}", [this](Request& r, const Respond& res) {
    const int n = tool_number(r.params.at(0));
    const tooling::Tool t = tool_from(parse_body(r), n);
    const bool existed = jobs_.tools().snapshot().by_number(n) != nullptr;
    try {
      jobs_.tools().put(t, true);
    } catch (const std::invalid_argument& e) {
      throw ApiError{409, "conflict", e.what()};
    }
    res(Response::json(existed ? 200 : 201, tool_json(t)));
  });
  router_.add("DELETE", "/api/v1/tools/{number}", [this](Request& r, const Respond& res) {
    const int n = tool_number(r.params.at(0));
    try {
      jobs_.tools().remove(n);
    } catch (const std::invalid_argument& e) {
      throw ApiError{404, "not_found", e.what()};
    }
    res(Response::json(200, {{"removed", n}}));
  });
  // {"name": "library.json" | "bit.fctb" | "tool.tbl", "content": "...", "replace": false, "inch": false}:
  // the format by the name's extension (a Vectric .vtdb is binary: import it with the CLI).
  router_.add("POST", "/api/v1/tools/import", [this](Request& r, const Respond& res) {
    const json b = parse_body(r);
    const std::string name = text(b, "name", 200);
    if (name.empty() || name.find('/') != std::string::npos) bad("name: required, the file's name (its extension says the format)");
    if (!b.contains("content") || !b.at("content").is_string()) bad("content: required, the file's text");
    const auto ext = std::filesystem::path(name).extension().string();
    if (ext == ".vtdb") bad("name: a Vectric .vtdb is an SQLite database: import it with `cncstream tools import`");
    // The importers read files: the text goes to a private temporary one named as given.
    const auto dir = std::filesystem::temp_directory_path() / ("cncstreamd-import-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    static std::atomic<unsigned> imports{0};
    const auto path = dir / (std::to_string(imports++) + "-" + name);
    {
      std::ofstream out(path, std::ios::binary);
      out << b.at("content").get<std::string>();
    }
    tooling::ImportResult result;
    try {
      result = tooling::import_tool_file(path, b.contains("inch") && b.at("inch").is_boolean() && b.at("inch").get<bool>());
    } catch (const std::exception& e) {
      std::error_code ec;
      std::filesystem::remove(path, ec);
      // The importer names the temporary file: the client is told its own file's name.
      std::string what = e.what();
      for (auto at = what.find(path.string()); at != std::string::npos; at = what.find(path.string(), at + name.size()))
        what.replace(at, path.string().size(), name);
      bad(what);
    }
    std::error_code ec;
    std::filesystem::remove(path, ec);
    const bool replace = b.contains("replace") && b.at("replace").is_boolean() && b.at("replace").get<bool>();
    const auto placed = jobs_.tools().merge(result, replace);
    res(Response::json(200, {{"format", result.format},
                             {"understood", result.understood},
                             {"skipped", result.skipped},
                             {"placed", placed}}));
  });
}

}  // namespace cncstream::daemon
