#pragma once
// Runs the real `cncstream` binary (from CNCSTREAM_BINARY_DIR) with a
// private journal and state folder, and captures its exit code and output.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace apptest {

namespace fs = std::filesystem;

inline fs::path temp_dir() {
  const auto d = fs::temp_directory_path() / ("cncstream_apps_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

inline std::string quote(const std::string& s) {
  std::ostringstream q;
  q << '\'';
  for (char c : s) {
    if (c == '\'') q << "'\\''";
    else q << c;
  }
  q << '\'';
  return q.str();
}

struct AppRun {
  int code = -1;
  std::string out;  // stdout and stderr, interleaved
  bool has(const std::string& s) const { return out.find(s) != std::string::npos; }
};

// `args` after the program name; stdin is /dev/null (no terminal). The
// journal and generated programs go to a per-test-process state folder.
inline AppRun run_cncstream(const std::vector<std::string>& args, int timeout_s = 60) {
  static int counter = 0;
  const fs::path log = temp_dir() / ("run" + std::to_string(counter++) + ".log");
  std::ostringstream cmd;
  cmd << "XDG_STATE_HOME=" << quote((temp_dir() / "state").string()) << " timeout -s KILL " << timeout_s << " "
      << quote((fs::path(CNCSTREAM_BINARY_DIR) / "cncstream").string());
  for (const auto& a : args) cmd << " " << quote(a);
  cmd << " </dev/null >" << quote(log.string()) << " 2>&1";
  const int st = std::system(cmd.str().c_str());
  AppRun r;
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::ifstream f(log);
  std::stringstream ss;
  ss << f.rdbuf();
  r.out = ss.str();
  return r;
}

inline std::string journal() { return (temp_dir() / "state" / "cncstream" / "journal.sqlite").string(); }

inline std::string plaque() { return (fs::path(CNCSTREAM_SOURCE_DIR) / "examples" / "plaque.stl").string(); }

}  // namespace apptest
