#pragma once
// The daemon's tool library: <data_dir>/tools.toml (tooling/tool_library.hpp),
// served over the API (GET/PUT/POST/DELETE /api/v1/tools, import) and used
// by a job's "tool", "rough" and "rest" when they name a tool. Each change is
// written whole before it is answered; a broken file stops the daemon at
// start with its line.
#include <filesystem>
#include <mutex>

#include "cncstream/tooling/tool_import.hpp"
#include "cncstream/tooling/tool_library.hpp"

namespace cncstream::daemon {

class ToolStore {
 public:
  // Empty path: an empty library that is not saved (tests without a data folder).
  explicit ToolStore(std::filesystem::path path);
  tooling::ToolLibrary snapshot() const;
  // As ToolLibrary::put / remove, then saved; throw std::invalid_argument.
  void put(const tooling::Tool& tool, bool replace);
  void remove(int number);
  // The lines merge_import reports.
  std::vector<std::string> merge(const tooling::ImportResult& import, bool replace);
  const std::filesystem::path& path() const { return path_; }

 private:
  void save() const;
  // Applies `f` to a copy, saves it, and only then keeps it (a failed save changes nothing).
  template <class F>
  auto change(F&& f);
  std::filesystem::path path_;
  mutable std::mutex mutex_;
  tooling::ToolLibrary library_;
};

}  // namespace cncstream::daemon
