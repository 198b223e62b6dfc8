#include "cncstream/protocol/profiles_dir.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>

#include "cncstream/protocol/firmware_profile.hpp"

// The profiles' install folder relative to the programs' (GNUInstallDirs:
// bin -> share/cncstream/firmware-profiles), set by CMake.
#ifndef CNCSTREAM_PROFILES_FROM_BINDIR
#error "CNCSTREAM_PROFILES_FROM_BINDIR must be defined by the build"
#endif

namespace cncstream::protocol {

namespace fs = std::filesystem;

std::vector<ProfilesPlace> profiles_search_order(const ProgramLocation& where) {
  if (where.env_profiles) return {{fs::path(*where.env_profiles), "CNCSTREAM_PROFILES"}};
  std::vector<ProfilesPlace> places;
  if (!where.exe.empty())  // unknown without /proc: a relative guess would depend on the working folder
    places.push_back({(where.exe.parent_path() / CNCSTREAM_PROFILES_FROM_BINDIR).lexically_normal(),
                      "installed beside " + where.exe.string()});
  if (where.build_source_dir)
    places.push_back({*where.build_source_dir / "firmware-profiles",
                      "source tree of the build folder " + where.exe.parent_path().string()});
  return places;
}

std::optional<fs::path> cncstream_source_dir_from_cache(std::string_view cmake_cache) {
  // project(cncstream) writes this entry; another project's cache has none.
  constexpr std::string_view kKey = "cncstream_SOURCE_DIR:STATIC=";
  std::size_t start = 0;
  while (start < cmake_cache.size()) {
    std::size_t end = cmake_cache.find('\n', start);
    if (end == std::string_view::npos) end = cmake_cache.size();
    std::string_view line = cmake_cache.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.starts_with(kKey) && line.size() > kKey.size()) return fs::path(line.substr(kKey.size()));
    start = end + 1;
  }
  return std::nullopt;
}

fs::path first_profiles_folder(const std::vector<ProfilesPlace>& places) {
  std::string looked;
  for (const ProfilesPlace& p : places) {
    std::error_code ec;
    if (fs::is_directory(p.dir, ec)) return p.dir;
    looked += "\n  " + p.dir.string() + " (" + p.why + "): " + (fs::exists(p.dir, ec) ? "not a folder" : "not found");
  }
  if (places.empty()) looked = "\n  nowhere (the program's own path, /proc/self/exe, is unreadable)";
  throw ProfileError("no firmware profile folder found; looked in:" + looked +
                     "\nset CNCSTREAM_PROFILES to a folder of firmware profiles (*.toml)");
}

namespace {

// The I/O edge: what the running program can learn about itself.
ProgramLocation this_program() {
  ProgramLocation where;
  if (const char* env = std::getenv("CNCSTREAM_PROFILES"); env && *env) where.env_profiles = env;
  std::error_code ec;
  where.exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return where;
  // A build folder has CMakeCache.txt beside the programs; an install has not.
  std::ifstream cache(where.exe.parent_path() / "CMakeCache.txt");
  if (cache) {
    std::ostringstream text;
    text << cache.rdbuf();
    where.build_source_dir = cncstream_source_dir_from_cache(text.str());
  }
  return where;
}

}  // namespace

fs::path default_profiles_dir() { return first_profiles_folder(profiles_search_order(this_program())); }

}  // namespace cncstream::protocol
