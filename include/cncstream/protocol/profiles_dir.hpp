#pragma once
// Where the firmware profiles are. The order of the places is a pure
// function of what the running program knows about itself; default_profiles_dir()
// (firmware_profile.hpp) gathers that (environment, /proc/self/exe, the build
// folder's CMakeCache.txt) and takes the first place that is a folder.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cncstream::protocol {

// One place the profiles may be, and why it is looked at.
struct ProfilesPlace {
  std::filesystem::path dir;
  std::string why;  // e.g. "CNCSTREAM_PROFILES", "installed beside /usr/bin/cncstream"
};

// What the program knows about where it runs.
struct ProgramLocation {
  std::optional<std::string> env_profiles;  // $CNCSTREAM_PROFILES, when set and not empty
  std::filesystem::path exe;                // the running program, absolute
  // The source tree when the program runs from a cncstream build folder
  // (its CMakeCache.txt names it); empty for an installed program.
  std::optional<std::filesystem::path> build_source_dir;
};

// CNCSTREAM_PROFILES alone when set (an override that is wrong must say so,
// not fall through); otherwise the installed folder relative to the program,
// then the source tree's firmware-profiles when running from a build folder.
std::vector<ProfilesPlace> profiles_search_order(const ProgramLocation& where);

// The source folder a CMakeCache.txt belongs to, when it is cncstream's.
std::optional<std::filesystem::path> cncstream_source_dir_from_cache(std::string_view cmake_cache);

// The first place that is a folder; ProfileError naming every place looked
// and why, when none is.
std::filesystem::path first_profiles_folder(const std::vector<ProfilesPlace>& places);

}  // namespace cncstream::protocol
