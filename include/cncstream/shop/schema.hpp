#pragma once
// The hub's schema: versioned migrations shipped with the program, applied
// by `cncstream shop init URL` (docs/shop.md).
#include <string>
#include <vector>

namespace cncstream::shop {

class PgConnection;

struct Migration {
  int version;
  const char* note;
  const char* sql;
};

// Every migration, oldest first.
const std::vector<Migration>& migrations();

// The newest version this program knows.
int schema_version_known();

struct MigrationResult {
  int from = 0;  // the hub's version before (0: empty)
  int to = 0;
};

// Creates or upgrades the hub's schema under an advisory lock (two PCs
// migrating at once wait for each other); each migration in its own
// transaction. Throws ShopError naming the migration that failed, or when
// the hub is newer than this program.
MigrationResult migrate(PgConnection& db);

// The hub's version (0 when the schema is not there); throws ShopError.
int hub_schema_version(PgConnection& db);

}  // namespace cncstream::shop
