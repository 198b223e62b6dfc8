#include "cncstream/daemon/ws_message.hpp"

#include "cncstream/daemon/body_fields.hpp"
#include "cncstream/daemon/json_body.hpp"

namespace cncstream::daemon {

using nlohmann::json;

WsMessage parse_ws_message(std::string_view text) {
  WsMessage m;
  json msg;
  try {
    msg = parse_json(text, "");
  } catch (const ApiError& e) {
    throw WsMessageError{e, nullptr};
  }
  if (!msg.is_object() || !msg.contains("type") || !msg.at("type").is_string())
    throw WsMessageError{{400, "bad_request", "expected an object with a string 'type'"}, nullptr};
  if (msg.contains("id")) m.id = msg.at("id");
  m.type = msg.at("type").get<std::string>();
  try {
    if (m.type == "ping") return m;
    if (m.type == "subscribe") {
      if (!msg.contains("machines") || !msg.at("machines").is_array())
        throw ApiError{400, "bad_request", "machines: expected an array"};
      for (const auto& n : msg.at("machines")) {
        if (!n.is_string()) throw ApiError{400, "bad_request", "machines: expected names"};
        m.machines.push_back(n.get<std::string>());
      }
      return m;
    }
    if (m.type == "jog_start" || m.type == "jog_renew" || m.type == "jog_release") {
      if (!msg.contains("machine") || !msg.at("machine").is_string())
        throw ApiError{400, "bad_request", "machine: required"};
      m.machine = msg.at("machine").get<std::string>();
      if (m.type == "jog_start") {
        m.dir = jog_direction(msg);
        m.feed = number_field(msg, "feed", 0, 100000);
      }
      return m;
    }
    throw ApiError{400, "bad_request", cat({"unknown message type '", m.type.substr(0, 40), "'"})};
  } catch (const ApiError& e) {
    throw WsMessageError{e, m.id};
  }
}

}  // namespace cncstream::daemon
