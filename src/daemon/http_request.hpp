#pragma once
// A request's header as Boost.Beast parsed it -> the Request the handlers see
// (path and query decoded, header names in lower case). Beast stays in the
// server's own files (this one and http_server.cpp); the fuzz target for
// HTTP requests parses bytes with Beast and calls this, as the server does.
#include <boost/beast/http/fields.hpp>
#include <boost/beast/http/message.hpp>

#include <cstddef>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

// The most a request's header may take (a larger one is answered 431).
inline constexpr std::size_t kMaxHeaderBytes = 16 * 1024;

// ok = false: the target is malformed (a bad escape, a NUL, no leading '/').
Request request_from(const boost::beast::http::request_header<>& h, bool& ok);

}  // namespace cncstream::daemon
