#pragma once
// Uploaded parts and programs, stored under <data>/files/ by their SHA-256.
// The name a client gives is a label kept in the metadata: it never becomes
// a path. Thread-safe (uploads are ingested on a worker, listed on the event
// loop).
#include <array>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace cncstream::daemon {

struct FileInfo {
  std::string id;    // 64 lowercase hex: the content's SHA-256
  std::string name;  // the client's label, sanitised
  std::string kind;  // "stl" | "gcode"
  std::uint64_t size = 0;
  std::size_t facets = 0;  // stl
  std::size_t lines = 0;   // gcode
  std::array<double, 6> bbox{};  // stl: x0 y0 z0 x1 y1 z1, mm as read (before units/scale)
  std::string uploaded_at;
};

class FileStoreError : public std::runtime_error {
 public:
  FileStoreError(int status, std::string code, const std::string& msg)
      : std::runtime_error(msg), status(status), code(std::move(code)) {}
  int status;
  std::string code;
};

// Control characters, '/', '\' and bytes that are not UTF-8 become '_'; at
// most 255 bytes, never cutting a character; "" -> "unnamed". (The label is
// stored and sent as JSON, which must be UTF-8.)
std::string sanitize_label(const std::string& name);
bool is_file_id(const std::string& s);  // 64 lowercase hex digits

class FileStore {
 public:
  explicit FileStore(std::filesystem::path dir);
  const std::filesystem::path& dir() const { return dir_; }
  // A fresh temporary path inside the store (same file system: the rename is atomic).
  std::filesystem::path temp_path();
  // Hashes and classifies a spooled upload and moves it into the store
  // (removing `temp`). Returns the info and whether the content was new.
  // Throws FileStoreError (415 for content that is neither STL nor G-code).
  std::pair<FileInfo, bool> ingest(const std::filesystem::path& temp, const std::string& label);
  std::vector<FileInfo> list() const;
  std::optional<FileInfo> get(const std::string& id) const;
  bool remove(const std::string& id);
  // The stored content's path (only for a valid id that exists).
  std::optional<std::filesystem::path> content_path(const std::string& id) const;

 private:
  std::optional<FileInfo> read_meta(const std::string& id) const;
  void write_meta(const FileInfo& f) const;
  std::filesystem::path dir_;
  mutable std::mutex mu_;
};

}  // namespace cncstream::daemon
