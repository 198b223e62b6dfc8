#include "cncstream/daemon/json_body.hpp"

#include <string>

namespace cncstream::daemon {

using nlohmann::json;

namespace {
struct TooDeep {};
}  // namespace

json parse_json(std::string_view text, std::string_view where) {
  // The callback sees each object or array start with the number of
  // containers already open around it.
  const json::parser_callback_t limit = [](int depth, json::parse_event_t event, json&) {
    if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
        depth >= kMaxJsonDepth)
      throw TooDeep{};
    return true;
  };
  try {
    return json::parse(text, limit);
  } catch (const json::parse_error& e) {
    throw ApiError{400, "bad_request", cat({"malformed JSON at byte ", std::to_string(e.byte), where})};
  } catch (const json::out_of_range&) {
    // A number beyond a double (1e500): not a parse_error, so it used to get
    // past the WebSocket handler's catch and out of the event loop.
    throw ApiError{400, "bad_request", cat({"a JSON number is out of range", where})};
  } catch (const TooDeep&) {
    throw ApiError{400, "bad_request", cat({"JSON nested deeper than ", std::to_string(kMaxJsonDepth), " levels", where})};
  }
}

json parse_body(const Request& r) {
  if (r.body.empty()) return json::object();
  return parse_json(r.body, " of the body");
}

}  // namespace cncstream::daemon
