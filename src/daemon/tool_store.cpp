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

void ToolStore::put(const tooling::Tool& tool, bool replace) {
  std::lock_guard lock(mutex_);
  tooling::ToolLibrary next = library_;
  next.put(tool, replace);
  std::swap(library_, next);
  try {
    save();
  } catch (...) {
    std::swap(library_, next);  // not saved: not changed
    throw;
  }
}

void ToolStore::remove(int number) {
  std::lock_guard lock(mutex_);
  tooling::ToolLibrary next = library_;
  next.remove(number);
  std::swap(library_, next);
  try {
    save();
  } catch (...) {
    std::swap(library_, next);
    throw;
  }
}

std::vector<std::string> ToolStore::merge(const tooling::ImportResult& import, bool replace) {
  std::lock_guard lock(mutex_);
  tooling::ToolLibrary next = library_;
  auto lines = tooling::merge_import(next, import, replace);
  std::swap(library_, next);
  try {
    save();
  } catch (...) {
    std::swap(library_, next);
    throw;
  }
  return lines;
}

}  // namespace cncstream::daemon
