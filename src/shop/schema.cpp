#include "cncstream/shop/schema.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "cncstream/shop/pg.hpp"

namespace cncstream::shop {

namespace {
// pg_advisory_lock's key for migrations (an arbitrary constant of ours).
constexpr const char* kMigrationLock = "SELECT pg_advisory_lock(6360029)";
constexpr const char* kMigrationUnlock = "SELECT pg_advisory_unlock(6360029)";
}  // namespace

int schema_version_known() { return migrations().back().version; }

int hub_schema_version(PgConnection& db) {
  const auto r = db.exec("SELECT to_regclass('public.cncstream_shop_schema') IS NOT NULL");
  if (r.text(0, 0) != "t") return 0;
  return static_cast<int>(db.exec("SELECT coalesce(max(version), 0) FROM public.cncstream_shop_schema").i64(0, 0));
}

MigrationResult migrate(PgConnection& db) {
  db.exec(kMigrationLock);
  MigrationResult res;
  try {
    db.exec("CREATE TABLE IF NOT EXISTS public.cncstream_shop_schema (version integer PRIMARY KEY,"
            " note text NOT NULL, applied_at timestamptz NOT NULL DEFAULT now())");
    res.from = hub_schema_version(db);
    if (res.from > schema_version_known())
      throw ShopError(fmt::format("shop hub {}: its schema is version {}, newer than this program's {}: upgrade cncstream",
                                  redact_url(db.url()), res.from, schema_version_known()));
    res.to = res.from;
    // Each migration the hub lacks, in ascending order: one added between two
    // that ran (branches merged) still runs.
    std::set<int> applied;
    const auto have = db.exec("SELECT version FROM public.cncstream_shop_schema");
    for (int i = 0; i < have.rows(); ++i) applied.insert(static_cast<int>(have.i64(i, 0)));
    int previous = 0;
    for (const auto& m : migrations()) {
      if (m.version <= previous)
        throw ShopError(fmt::format("the shop's migrations are out of order: {} after {}", m.version, previous));
      previous = m.version;
      if (applied.count(m.version)) continue;
      db.exec("BEGIN");
      try {
        db.exec(m.sql);
        db.exec("INSERT INTO public.cncstream_shop_schema (version, note) VALUES ($1, $2)",
                {std::to_string(m.version), std::string(m.note)});
        db.exec("COMMIT");
      } catch (const ShopError& e) {
        if (db.ok()) db.exec("ROLLBACK");
        throw ShopError(fmt::format("migration {} ({}): {}", m.version, m.note, e.what()));
      }
      res.to = std::max(res.to, m.version);
    }
  } catch (...) {
    if (db.ok()) db.exec(kMigrationUnlock);
    throw;
  }
  db.exec(kMigrationUnlock);
  return res;
}

}  // namespace cncstream::shop
