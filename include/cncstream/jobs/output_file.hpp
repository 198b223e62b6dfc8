#pragma once
// Output files written whole or not at all: into a temporary file beside the
// target, renamed over it once complete. A reader never sees half a file, and
// a job cancelled or failing half-way leaves none that looks complete.
#include <filesystem>
#include <functional>
#include <string_view>

namespace cncstream::jobs {

// `write` fills the file it is given (any writer that takes a path, such as
// write_png); on success that file becomes `path`, on an exception it is
// removed and the exception goes on. A target that exists and is not a
// regular file (a terminal, /dev/stdout, a FIFO) is written directly.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& file)>& write);

// Text as is (binary mode). Throws std::runtime_error "<path>: cannot open for
// writing" or "<path>: write failed".
void write_text_file_atomically(const std::filesystem::path& path, std::string_view text);

}  // namespace cncstream::jobs
