// The daemon's pure request checks (what tests/fuzz drives): JSON with a
// nesting limit, numbers beyond a double, WebSocket messages, answers that
// quote bytes which are not UTF-8, upload labels, and configuration table
// headers. Each case here is one the fuzz targets found or guard.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "cncstream/daemon/config.hpp"
#include "cncstream/daemon/file_store.hpp"
#include "cncstream/daemon/json_body.hpp"
#include "cncstream/daemon/ws_message.hpp"

using namespace cncstream::daemon;
using nlohmann::json;

namespace {

std::string nested(int depth) { return std::string(static_cast<std::size_t>(depth), '[') + std::string(static_cast<std::size_t>(depth), ']'); }

std::string api_error(const std::string& text) {
  try {
    (void)parse_json(text, " of the body");
  } catch (const ApiError& e) {
    EXPECT_EQ(e.status, 400);
    return e.message;
  }
  return "";
}

bool valid_utf8(const std::string& s) {
  try {
    (void)json(s).dump();  // strict: throws on bytes that are not UTF-8
    return true;
  } catch (const json::type_error&) {
    return false;
  }
}

}  // namespace

TEST(JsonBody, NestingBeyondTheLimitIsRefusedBeforeAnythingRecursesOverIt) {
  EXPECT_EQ(parse_json(nested(kMaxJsonDepth), "").dump(), nested(kMaxJsonDepth));
  EXPECT_EQ(api_error(nested(kMaxJsonDepth + 1)), "JSON nested deeper than 32 levels of the body");
  // A megabyte of '[' (a body at its size limit) is refused, not parsed into a value to recurse over.
  EXPECT_EQ(api_error(std::string(1 << 20, '[')), "JSON nested deeper than 32 levels of the body");
  EXPECT_EQ(api_error(R"({"a": {"b": [1, 2, )").rfind("malformed JSON at byte ", 0), 0u);
}

TEST(JsonBody, ANumberBeyondADoubleIs400) {
  // Found by fuzz_job_params and fuzz_ws_message: nlohmann throws out_of_range, not parse_error.
  EXPECT_EQ(api_error(R"({"tool": "ball:3", "feed": 1e500})"), "a JSON number is out of range of the body");
  EXPECT_EQ(api_error("-1e400"), "a JSON number is out of range of the body");
}

TEST(WsMessage, IsCheckedFieldByFieldAndRefusalsKeepTheId) {
  const WsMessage ping = parse_ws_message(R"({"type": "ping", "id": {"n": [1, "x"]}})");
  EXPECT_EQ(ping.type, "ping");
  EXPECT_EQ(ping.id, json({{"n", {1, "x"}}}));
  const WsMessage jog = parse_ws_message(R"({"type": "jog_start", "machine": "sim1", "dir": [0, -1, 0.5], "feed": 800})");
  EXPECT_EQ(jog.machine, "sim1");
  EXPECT_EQ(jog.dir.v[1], -1);
  EXPECT_EQ(jog.feed, 800);
  EXPECT_EQ(parse_ws_message(R"({"type": "subscribe", "machines": ["*", "sim2"]})").machines.size(), 2u);
  auto refusal = [](const std::string& text) {
    try {
      (void)parse_ws_message(text);
    } catch (const WsMessageError& e) {
      EXPECT_EQ(e.error.status, 400) << text;
      return json{{"id", e.id}, {"message", e.error.message}};
    }
    ADD_FAILURE() << text << " was accepted";
    return json();
  };
  EXPECT_EQ(refusal(R"({"type": "jog_start", "machine": "sim1", "dir": [0, 0, 0], "feed": 800, "id": 4})"),
            json({{"id", 4}, {"message", "dir: all zero"}}));
  EXPECT_EQ(refusal(R"({"type": "jog_start", "machine": "sim1", "dir": [1, 0, 0], "feed": 0, "id": "j"})"),
            json({{"id", "j"}, {"message", "feed: must be > 0 and <= 100000"}}));
  EXPECT_EQ(refusal(R"({"type": "subscribe", "machines": ["sim1", 2], "id": 5})")["message"], "machines: expected names");
  EXPECT_EQ(refusal(R"({"type": "format", "id": 6})")["message"], "unknown message type 'format'");
  EXPECT_EQ(refusal(R"(["ping"])")["message"], "expected an object with a string 'type'");
  // Found by fuzz_ws_message: a number beyond a double in the id escaped the
  // handler (out_of_range is no parse_error) and the event loop with it.
  EXPECT_EQ(refusal(R"({"type": "ping", "id": 1e500})"), json({{"id", nullptr}, {"message", "a JSON number is out of range"}}));
  // An id nested 60,000 deep overflowed the stack when the pong echoed it.
  EXPECT_EQ(refusal(R"({"type": "ping", "id": )" + nested(60000) + "}")["message"], "JSON nested deeper than 32 levels");
}

TEST(DumpJson, BytesThatAreNotUtf8AreReplacedNotThrown) {
  // A percent-decoded path or a header quoted in an error: nlohmann's dump()
  // throws on them, which took the daemon down from the event loop.
  Response r;
  ASSERT_NO_THROW(r = Response::error(404, "not_found", "no route /\xff\xfe"));
  EXPECT_NE(r.body.find("no route /\xEF\xBF\xBD\xEF\xBF\xBD"), std::string::npos) << r.body;
  EXPECT_EQ(dump_json(json("caf\xC3\xA9")), "\"caf\xC3\xA9\"");
}

TEST(FileStore, LabelsAreUtf8AndNeverCutACharacter) {
  EXPECT_EQ(sanitize_label("plaque \xC3\xA9t\xC3\xA9.stl"), "plaque \xC3\xA9t\xC3\xA9.stl");
  EXPECT_EQ(sanitize_label("a\xff" "b\xC3" "c\xED\xA0\x80" "d\xF4\x90\x80\x80"), "a_b_c___d____");
  EXPECT_EQ(sanitize_label("\xC0\xAF"), "__");  // an overlong '/'
  // 254 bytes, then a two-byte character that would end at byte 256: left out, not cut.
  const std::string label = sanitize_label(std::string(254, 'x') + "\xC3\xA9");
  EXPECT_EQ(label, std::string(254, 'x'));
  for (const std::string& s : {std::string("\xff\xfe"), std::string(300, '\xC3'), std::string(253, 'x') + "\xE2\x82\xAC\xE2\x82\xAC"})
    EXPECT_TRUE(valid_utf8(sanitize_label(s)));
}

TEST(Config, ATableHeaderThatDoesNotStartWithAKeyIsRefusedNamingTheLine) {
  // Found by fuzz_daemon_config: toml++ 3.3 asserts on it (undefined behaviour in a release build).
  try {
    (void)parse_config("listen = \"127.0.0.1:8420\"\n\n[[)achine]]\nname = \"router\"\n", "d.toml");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "d.toml:3: a table header must start with a key (a letter, digit, _, - or a quote)");
  }
  EXPECT_EQ(parse_config("[ \"limits\" ]\nmax_connections = 3\n", "d.toml").limits.max_connections, 3u);
  // A line of an array value that starts with '[' is no table header: toml++
  // parses it, and the reader refuses the key for what it is.
  try {
    (void)parse_config("x = [\n[+1],\n]\n", "d.toml");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "d.toml:1: unknown key 'x'");
  }
}

TEST(Config, ACharacterBeyondAsciiOutsideAStringIsRefusedNamingTheLine) {
  // Found by fuzz_daemon_config: toml++ 3.3 reaches an unreachable branch of its whitespace test.
  auto error = [](const std::string& text) -> std::string {
    try {
      (void)parse_config(text, "d.toml");
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("[[machine]]\nname = r\xC3\xA9\n"),
            "d.toml:2: a character beyond ASCII outside a string or comment (quote the value)");
  EXPECT_EQ(error("[security]\nallowed_hosts = [\"a\", \xC3\xA9]\n"),
            "d.toml:2: a character beyond ASCII outside a string or comment (quote the value)");
  // A quote inside a bare value starts no string (toml++ scans through it), nor does an escape take one.
  EXPECT_EQ(error("[security]\nrequire_token = 1\"\xC3\xA9\"\n"),
            "d.toml:2: a character beyond ASCII outside a string or comment (quote the value)");
  EXPECT_EQ(error("[web]\nroot = \"\"\"\\\xC3\xA9\"\"\"\n"), "d.toml:2: a character beyond ASCII right after a backslash (toml++ 3.3 cannot read it)");
  // Valid TOML, but toml++ skips the blanks after a line-ending backslash with its faulty whitespace test.
  EXPECT_EQ(error("[web]\nroot = \"\"\"x \\\n  \xC3\xA9\"\"\"\n"),
            "d.toml:2: a character beyond ASCII right after a backslash (toml++ 3.3 cannot read it)");
  EXPECT_EQ(error(std::string("[web]\nroot = x") + '\0' + "\"\xC3\xA9\"\n"),
            "d.toml:2: a character beyond ASCII outside a string or comment (quote the value)");
  // Found by fuzz_daemon_config: toml++ 3.3 asserts on an array element starting with '}'.
  EXPECT_EQ(error("[security]\nallowed_hosts = [ # hosts\n}]\n"), "d.toml:3: '}' where an array's element belongs");
  // Found by fuzz_daemon_config: toml++ 3.3 asserts on a date, a space and one digit; a real time passes.
  EXPECT_EQ(error("[limits]\nmax_connections = 2051-06-01 0 \n"),
            "d.toml:2: a date followed by a lone digit (write the time as HH:MM:SS)");
  EXPECT_EQ(error("x = 1979-05-27 07:32:00 # a date-time\n"), "d.toml:1: unknown key 'x'");
  // In strings and comments they are text like any other.
  const auto c = parse_config(
      "# l'\xC3\xA9tabli\n[security]\nallowed_hosts = [\"caf\xC3\xA9.local\", '\xC3\xA9', \"\"\"\n\xC3\xA9\"\"\"\"]  # \xC3\xA9\n",
      "d.toml");
  ASSERT_EQ(c.security.allowed_hosts.size(), 3u);
  EXPECT_EQ(c.security.allowed_hosts[0], "caf\xC3\xA9.local");
  EXPECT_EQ(c.security.allowed_hosts[2], "\xC3\xA9\"");
}

TEST(Config, TheDocumentedExamplesPassTheTextCheck) {
  // The fuzz seeds: api-v1.md's configuration and a pendant's section, with
  // strings, comments, arrays, an IPv6 listen address.
  auto read = [](const char* name) {
    std::ifstream in(std::string(CNCSTREAM_SOURCE_DIR) + "/tests/fuzz/corpus/fuzz_daemon_config/" + name);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  };
  const auto doc = parse_config(read("api_v1_example.toml"), "api_v1_example.toml");
  EXPECT_EQ(doc.machines.size(), 2u);
  EXPECT_EQ(doc.limits.max_grid_nodes, 50e6);
  const auto pendant = parse_config(read("pendant.toml"), "pendant.toml");
  ASSERT_EQ(pendant.pendants.size(), 1u);
  EXPECT_EQ(pendant.pendants[0].macros.size(), 2u);
  EXPECT_EQ(pendant.listen_address, "::1");
  // Inline tables and arrays nest; keys in them may be quoted.
  EXPECT_THROW((void)parse_config("[web]\nroot = { \"a\" = [1, [2, \"\xC3\xA9\"]], b.\"c\" = 'd' }\n", "d.toml"),
               std::invalid_argument);  // a table is no path: the reader says so, not the text check
  try {
    (void)parse_config("[web]\nroot = { \"a\" = [1, [2, \"\xC3\xA9\"]], b.\"c\" = 'd' }\n", "d.toml");
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "d.toml:2: web.root: expected a string");
  }
}
