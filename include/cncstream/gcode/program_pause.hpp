#pragma once
// What a program says to the operator where it pauses: an M0 line and the
// comments just before it (a tool change's "mount T2 ..."). A streamer shows
// it when the controller holds on that line.
#include <optional>
#include <string>
#include <vector>

namespace cncstream::gcode {

// Whether the line's words (comments left out) hold M0 (or M00).
bool is_program_pause(const std::string& line);

// Whether the line holds no words at all (blank or comments only): a
// streamer may leave it out, so no answer marks its place.
bool has_no_words(const std::string& line);

// If lines[index] is a program pause: the text of the comment lines just
// before it (T words between them are skipped), in order, joined by a
// space; an empty string if there are none. nullopt if it is not a pause
// or index is out of range.
std::optional<std::string> program_pause_note(const std::vector<std::string>& lines, std::size_t index);

}  // namespace cncstream::gcode
