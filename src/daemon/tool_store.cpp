#include "cncstream/daemon/tool_store.hpp"

#include "cncstream/jobs/output_file.hpp"

namespace cncstream::daemon {

ToolStore::ToolStore(std::filesystem::path path) : path_(std::move(path)) {
  if (!path_.empty()) library_ = tooling::load_tool_library(path_);
}

tooling::ToolLibrary ToolStore::snapshot() const {
  std::lock_guard lock(mutex_);
  return library_;
}

void ToolStore::save() const {
  if (!path_.empty()) jobs::write_text_file_atomically(path_, tooling::format_tool_library(library_));
}

template <class F>
auto ToolStore::change(F&& f) {
  std::lock_guard lock(mutex_);
  tooling::ToolLibrary next = library_;
  auto result = f(next);
  std::swap(library_, next);
  try {
    save();
  } catch (...) {
    std::swap(library_, next);
    throw;
  }
  return result;
}

void ToolStore::put(const tooling::Tool& tool, bool replace) {
  change([&](tooling::ToolLibrary& lib) {
    lib.put(tool, replace);
    return 0;
  });
}

void ToolStore::remove(int number) {
  change([&](tooling::ToolLibrary& lib) {
    lib.remove(number);
    return 0;
  });
}

std::vector<std::string> ToolStore::merge(const tooling::ImportResult& import, bool replace) {
  return change([&](tooling::ToolLibrary& lib) { return tooling::merge_import(lib, import, replace); });
}

}  // namespace cncstream::daemon
