#pragma once
// The simulator's output files (machined surface, deviation map) written
// whole or not at all: into a temporary file beside the target, renamed over
// it once complete, so that a run stopped half-way leaves no file that looks
// complete. (The jobs layer has its own, which the simulator may not use.)
#include <filesystem>
#include <functional>

namespace cncsim {

// `write` fills the file it is given; on success that file becomes `path`,
// on an exception it is removed and the exception goes on.
void write_whole(const std::filesystem::path& path, const std::function<void(const std::filesystem::path& file)>& write);

}  // namespace cncsim
