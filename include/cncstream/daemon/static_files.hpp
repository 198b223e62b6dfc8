#pragma once
// The web page's files: GET / and /static/<path> from the web root.
#include <filesystem>
#include <optional>
#include <string>

namespace cncstream::daemon {

// The content type for a file name's extension.
std::string content_type_for(const std::filesystem::path& p);
// A request's path below the web root, or nullopt for anything that could
// leave it ("..", "\\", NUL, an absolute path, a hidden file).
std::optional<std::filesystem::path> safe_static_path(const std::filesystem::path& root, const std::string& rel);

}  // namespace cncstream::daemon
