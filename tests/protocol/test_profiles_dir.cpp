#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "cncstream/protocol/firmware_profile.hpp"
#include "cncstream/protocol/profiles_dir.hpp"

using namespace cncstream::protocol;
namespace fs = std::filesystem;

TEST(ProfilesDir, EnvironmentOverridesAlone) {
  ProgramLocation w;
  w.env_profiles = "/opt/profiles";
  w.exe = "/usr/bin/cncstream";
  w.build_source_dir = "/src/cncstream";
  const auto places = profiles_search_order(w);
  ASSERT_EQ(places.size(), 1u);
  EXPECT_EQ(places[0].dir, fs::path("/opt/profiles"));
}

TEST(ProfilesDir, InstalledBesideTheProgramThenTheBuildsSourceTree) {
  ProgramLocation w;
  w.exe = "/usr/local/bin/cncstream";
  auto places = profiles_search_order(w);
  ASSERT_EQ(places.size(), 1u);  // an installed program knows no source tree
  EXPECT_EQ(places[0].dir, fs::path("/usr/local/share/cncstream/firmware-profiles"));
  w.exe = "/home/me/cncstream/build/release/cncstream";
  w.build_source_dir = "/home/me/cncstream";
  places = profiles_search_order(w);
  ASSERT_EQ(places.size(), 2u);
  EXPECT_EQ(places[0].dir, fs::path("/home/me/cncstream/build/share/cncstream/firmware-profiles"));
  EXPECT_EQ(places[1].dir, fs::path("/home/me/cncstream/firmware-profiles"));
}

TEST(ProfilesDir, SourceTreeFromThisProjectsCacheOnly) {
  EXPECT_EQ(cncstream_source_dir_from_cache("# CMake cache\ncncstream_BINARY_DIR:STATIC=/b\n"
                                            "cncstream_SOURCE_DIR:STATIC=/src/cnc stream\r\nX:BOOL=ON\n"),
            fs::path("/src/cnc stream"));
  EXPECT_FALSE(cncstream_source_dir_from_cache("other_SOURCE_DIR:STATIC=/src/other\n"));
  EXPECT_FALSE(cncstream_source_dir_from_cache(""));
}

TEST(ProfilesDir, NoFolderNamesEveryPlaceLooked) {
  const fs::path tmp = fs::temp_directory_path() / ("cncstream_profiles_dir_" + std::to_string(::getpid()));
  fs::create_directories(tmp / "b");
  const std::vector<ProfilesPlace> places{{tmp / "a", "first reason"}, {tmp / "b", "second reason"}};
  EXPECT_EQ(first_profiles_folder(places), tmp / "b");
  try {
    first_profiles_folder({places[0], {tmp / "c", "third reason"}});
    FAIL() << "no folder: expected ProfileError";
  } catch (const ProfileError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find((tmp / "a").string() + " (first reason): not found"), std::string::npos) << m;
    EXPECT_NE(m.find((tmp / "c").string() + " (third reason): not found"), std::string::npos) << m;
    EXPECT_NE(m.find("CNCSTREAM_PROFILES"), std::string::npos) << m;
  }
  fs::remove_all(tmp);
}

TEST(ProfilesDir, BuildTreeProgramFindsTheSourceProfiles) {
  // The tests run from the build folder, without CNCSTREAM_PROFILES.
  ::unsetenv("CNCSTREAM_PROFILES");
  EXPECT_EQ(fs::canonical(default_profiles_dir()), fs::canonical(fs::path(CNCSTREAM_SOURCE_DIR) / "firmware-profiles"));
}
