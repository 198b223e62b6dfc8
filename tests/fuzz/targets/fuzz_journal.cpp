// What the resume planner reads back from a journal: the modal state stored
// as words, and a journal database file whose bytes are damaged.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cncstream/gcode/modal_words.hpp"
#include "cncstream/transport/journal.hpp"

using namespace cncstream;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // Words: the fields split on '|' (units|distance|plane|wcs|motion|feed_mode|spindle|coolant).
  gcode::ModalWords w;
  std::string* fields[] = {&w.units, &w.distance, &w.plane, &w.wcs, &w.motion, &w.feed_mode, &w.spindle, &w.coolant};
  std::size_t start = 0;
  for (auto* f : fields) {
    const std::size_t end = std::min(bytes.find('|', start), bytes.size());
    *f = std::string(bytes.substr(start, end - start));
    start = std::min(end + 1, bytes.size());
  }
  try {
    (void)gcode::modal_from_words(w);
  } catch (const std::invalid_argument&) {
  }
  // A database file with these bytes: opened and read, or a JournalError.
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("cncstream_fuzz_journal_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto path = dir / "journal.sqlite";
  std::filesystem::remove(path.string() + "-wal");
  std::filesystem::remove(path.string() + "-shm");
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  try {
    transport::Journal j(path);
    for (const auto& job : j.jobs(5)) (void)j.last_progress(job.id);
  } catch (const transport::JournalError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
