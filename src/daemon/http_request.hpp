#pragma once
// A request's header as Boost.Beast parsed it -> the Request the handlers see
// (path and query decoded, header names in lower case). Beast stays in the
// server's own files (this one and http_server.cpp); the fuzz target for
// HTTP requests parses bytes with Beast and calls this, as the server does.
#include <boost/beast/http/fields.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/optional.hpp>

#include <cstddef>
#include <cstdint>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

// The most a request's header may take (a larger one is answered 431).
inline constexpr std::size_t kMaxHeaderBytes = std::size_t{16} * 1024;

// ok = false: the target is malformed (a bad escape, a NUL, no leading '/').
Request request_from(const boost::beast::http::request_header<>& h, bool& ok);

// Whether a request declares a Content-Length beyond `limit`. Beast checks
// its body limit against Content-Length only when the header completes, and
// the server reads headers with none (an upload's limit is not a JSON
// body's), so a JSON body's declared length is checked with this before a
// byte of it is read: Beast's string body reserves the declared length
// (Content-Length: 4230881649935282631 threw bad_alloc out of the event loop,
// found by fuzz_http_request) and reads it all.
inline bool declared_beyond(const boost::optional<std::uint64_t>& content_length, std::uint64_t limit) {
  return content_length && *content_length > limit;
}

}  // namespace cncstream::daemon
