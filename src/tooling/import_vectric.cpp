// Vectric tool database (.vtdb, SQLite), as open projects that read and
// write it describe it (no published specification): tool_geometry (id,
// name_format, tool_type, units, diameter, num_flutes, flute_length,
// included_angle, flat_diameter, tip_radius), tool_cutting_data (id,
// feed_rate, plunge_rate, spindle_speed, stepdown, stepover, rate_units,
// length_units, tool_number), tool_entity (material_id, machine_id,
// tool_geometry_id, tool_cutting_data_id: the row with no material carries
// the tool number) and material (id, name). tool_type: 0 ball nose, 1 end
// mill, 2 radiused, 3 V-bit, 5 tapered ball nose (6 drill, 7 thread mill,
// 8 form tool, 9 diamond drag are skipped). units: 0 mm, 1 inch.
// rate_units: 0 mm/s, 1 mm/min, 2 m/min, 3 in/s, 4 in/min, 5 ft/min (4 is
// confirmed by a published test: 100 in/min -> 2540 mm/min; the others by
// their order). Columns are read by name, so a database with more columns
// or another order reads the same.
#include <fmt/format.h>
#include <sqlite3.h>

#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "cncstream/tooling/tool_import.hpp"
#include "import_common.hpp"

namespace cncstream::tooling {

namespace detail_vectric {

struct Value {
  std::optional<double> number;
  std::optional<std::string> text;
};
using Row = std::map<std::string, Value>;

class Database {
 public:
  explicit Database(const std::filesystem::path& path) : source_(path.string()) {
    if (sqlite3_open_v2(source_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw std::invalid_argument(fmt::format("{}: cannot open as an SQLite database ({})", source_, why));
    }
  }
  ~Database() { sqlite3_close(db_); }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  bool has_table(const std::string& name) {
    bool found = false;
    query("SELECT name FROM sqlite_master WHERE type = 'table' AND name = ?", {name},
          [&](const Row&) { found = true; });
    return found;
  }

  template <class F>
  void query(const std::string& sql, const std::vector<std::string>& args, F&& each) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &st, nullptr) != SQLITE_OK) {
      const std::string why = sqlite3_errmsg(db_);
      sqlite3_finalize(st);
      throw std::invalid_argument(fmt::format("{}: not a Vectric tool database ({}: {})", source_, sql, why));
    }
    for (std::size_t k = 0; k < args.size(); ++k)
      sqlite3_bind_text(st, static_cast<int>(k + 1), args[k].c_str(), -1, SQLITE_TRANSIENT);
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
      Row row;
      for (int c = 0; c < sqlite3_column_count(st); ++c) {
        Value v;
        switch (sqlite3_column_type(st, c)) {
          case SQLITE_INTEGER:
          case SQLITE_FLOAT: v.number = sqlite3_column_double(st, c); break;
          case SQLITE_TEXT: {
            const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(st, c));
            v.text = std::string(t ? t : "");
            // A number stored as text reads as a number too.
            try {
              std::size_t used = 0;
              const double d = std::stod(*v.text, &used);
              if (used == v.text->size()) v.number = d;
            } catch (const std::exception&) {
            }
            break;
          }
          case SQLITE_BLOB: {
            // Vectric keys rows by 16-byte GUIDs: compared as hex.
            const auto* b = static_cast<const unsigned char*>(sqlite3_column_blob(st, c));
            std::string hex;
            for (int i = 0; i < sqlite3_column_bytes(st, c); ++i) hex += fmt::format("{:02x}", b[i]);
            v.text = hex;
            break;
          }
          default: break;
        }
        row[sqlite3_column_name(st, c)] = v;
      }
      each(row);
    }
    const std::string why = rc == SQLITE_DONE ? std::string() : sqlite3_errmsg(db_);
    sqlite3_finalize(st);
    if (rc != SQLITE_DONE) throw std::invalid_argument(fmt::format("{}: reading failed ({})", source_, why));
  }

 private:
  std::string source_;
  sqlite3* db_ = nullptr;
};

std::optional<double> num(const Row& r, const char* key) {
  const auto it = r.find(key);
  return it == r.end() ? std::nullopt : it->second.number;
}
std::string text(const Row& r, const char* key) {
  const auto it = r.find(key);
  if (it == r.end()) return {};
  if (it->second.text) return *it->second.text;
  if (it->second.number) return fmt::format("{:g}", *it->second.number);
  return {};
}

// rate_units -> factor to mm/min.
std::optional<double> rate_factor(int units) {
  switch (units) {
    case 0: return 60.0;
    case 1: return 1.0;
    case 2: return 1000.0;
    case 3: return 25.4 * 60;
    case 4: return 25.4;
    case 5: return 304.8;
    default: return std::nullopt;
  }
}

}  // namespace detail_vectric

ImportResult import_vectric_database(const std::filesystem::path& path) {
  using namespace detail_vectric;
  ImportResult r;
  r.format = "Vectric tool database";
  const std::string source = path.string();
  Database db(path);
  for (const char* table : {"tool_geometry", "tool_entity", "tool_cutting_data"})
    if (!db.has_table(table))
      throw std::invalid_argument(fmt::format("{}: not a Vectric tool database: no table '{}'", source, table));
  std::map<std::string, std::string> materials;
  if (db.has_table("material"))
    db.query("SELECT * FROM material", {}, [&](const Row& m) { materials[text(m, "id")] = text(m, "name"); });

  std::vector<Row> geometries;
  db.query("SELECT * FROM tool_geometry", {}, [&](const Row& g) { geometries.push_back(g); });
  std::size_t index = 0;
  for (const Row& g : geometries) {
    ++index;
    const std::string id = text(g, "id");
    const std::string name_format = text(g, "name_format");
    const std::string entry = fmt::format("tool_geometry row {} '{}'", index, name_format);
    const auto type = num(g, "tool_type");
    const double scale = num(g, "units").value_or(0) == 1 ? 25.4 : 1.0;
    auto len = [&](const char* key) { return num(g, key).value_or(0) * scale; };
    Tool t;
    ToolGeometry& geo = t.geometry;
    geo.diameter = len("diameter");
    switch (type ? static_cast<int>(*type) : -1) {
      case 0: geo.shape = ToolShape::Ball; break;
      case 1: geo.shape = ToolShape::Flat; break;
      case 2:
        geo.shape = ToolShape::Bull;
        geo.corner_radius = len("tip_radius");
        if (geo.corner_radius <= 0) geo.shape = ToolShape::Flat;
        else if (geo.corner_radius >= geo.diameter / 2) geo.shape = ToolShape::Ball;
        break;
      case 3:
        geo.shape = ToolShape::VBit;
        geo.angle = num(g, "included_angle").value_or(0);
        geo.tip_diameter = len("flat_diameter");
        break;
      case 5:
        geo.shape = ToolShape::TaperedBall;
        geo.tip_diameter = 2 * len("tip_radius");
        geo.angle = num(g, "included_angle").value_or(0) / 2;  // included -> per side
        break;
      default:
        r.skipped.push_back(fmt::format("{}: tool type {} ({}) has no cutter here (ball nose, end mill, radiused, "
                                        "V-bit and tapered ball nose are imported)",
                                        entry, type ? fmt::format("{:g}", *type) : std::string("none"),
                                        !type                ? "missing"
                                        : *type == 6         ? "drill"
                                        : *type == 7         ? "thread mill"
                                        : *type == 8         ? "form tool"
                                        : *type == 9         ? "diamond drag"
                                                             : "unknown"));
        continue;
    }
    if (const auto f = num(g, "num_flutes"); f && *f >= 1) t.flutes = static_cast<int>(std::lround(*f));
    t.flute_length = len("flute_length");
    // Vectric names are templates ("{Tool Type} {Diameter|F} {Units Short}"): a name of our own then.
    t.name = name_format.empty() || name_format.find('{') != std::string::npos ? geo.description() : name_format;
    std::vector<std::string> with;
    db.query("SELECT * FROM tool_entity WHERE tool_geometry_id = ?", {id}, [&](const Row& e) {
      const std::string material_id = text(e, "material_id");
      db.query("SELECT * FROM tool_cutting_data WHERE id = ?", {text(e, "tool_cutting_data_id")}, [&](const Row& c) {
        if (const auto n = num(c, "tool_number"); n && *n >= 1 && *n <= 9999 && (t.number == 0 || material_id.empty()))
          t.number = static_cast<int>(*n);
        if (material_id.empty()) return;  // the master row: the number only
        const auto m = materials.find(material_id);
        CuttingData d;
        d.material = m != materials.end() && !m->second.empty() ? m->second : material_id;
        if (t.cutting_for(d.material)) return;
        const auto rate = rate_factor(static_cast<int>(num(c, "rate_units").value_or(1)));
        if (!rate) {
          r.skipped.push_back(fmt::format("{}: cutting data for {}: unknown rate_units {}", entry, d.material,
                                          text(c, "rate_units")));
          return;
        }
        const double lscale = num(c, "length_units") ? (*num(c, "length_units") == 1 ? 25.4 : 1.0) : scale;
        auto pos = [](std::optional<double> v, double s) -> std::optional<double> {
          if (v && *v > 0) return *v * s;
          return std::nullopt;
        };
        d.feed = pos(num(c, "feed_rate"), *rate);
        d.plunge_feed = pos(num(c, "plunge_rate"), *rate);
        d.rpm = pos(num(c, "spindle_speed"), 1);
        d.stepdown = pos(num(c, "stepdown"), lscale);
        d.stepover = pos(num(c, "stepover"), lscale);
        with.push_back(d.material);
        t.cutting.push_back(d);
      });
    });
    std::string extra;
    if (!with.empty()) {
      extra = ", cutting data for";
      for (std::size_t k = 0; k < with.size(); ++k) {
        extra.append(k ? ", " : " ");
        extra.append(with[k]);
      }
    }
    detail_import_common::accept_tool(r, std::move(t), entry, extra);
  }
  return r;
}

}  // namespace cncstream::tooling
