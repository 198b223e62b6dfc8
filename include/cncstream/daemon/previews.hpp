#pragma once
// Job previews: a program's tool-tip heights as a colour PNG and its path
// thinned for drawing (JSON), computed on the worker pool and cached per
// program (by its SHA-256) and size. Called on the event loop's thread; the
// answers come later (Respond may be called from any thread). Requests for
// the same picture while it is being made wait for that one.
#include <boost/asio/io_context.hpp>
#include <boost/asio/thread_pool.hpp>

#include <cstddef>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cncstream/daemon/http_types.hpp"

namespace cncstream::daemon {

struct Program;

class Previews {
 public:
  // The PNG's long side: at most this many pixels (and by default), at least kMinPixels.
  static constexpr int kMaxPixels = 1024, kMinPixels = 16;
  // The path's points: by default, and the bounds a request may ask for.
  static constexpr std::size_t kDefaultPoints = 20000, kMinPoints = 2, kMaxPoints = 200000;

  Previews(boost::asio::io_context& io, boost::asio::thread_pool& pool);
  ~Previews();
  Previews(const Previews&) = delete;
  Previews& operator=(const Previews&) = delete;

  // 200 image/png, the long side max_px (kMinPixels..kMaxPixels); 404 when
  // the program has no cutting move. A program whose heights are not known
  // yet (a G-code program before its trace after `ready` is done) is traced
  // for it, and keeps them.
  void png(const std::shared_ptr<const Program>& program, int max_px, Respond respond);
  // 200 JSON {"points", "total_points", "cuts": [[x, y, z, x, y, z, ...], ...], "rapids": [...]}.
  void path(const std::shared_ptr<const Program>& program, std::size_t max_points, Respond respond);

 private:
  using Bytes = std::shared_ptr<const std::string>;
  struct Lru {
    std::size_t capacity;
    std::list<std::pair<std::string, Bytes>> items;  // least recently used first
    Bytes get(const std::string& key);
    void put(const std::string& key, Bytes value);
  };
  // Answers from the cache, or joins (or starts) the computation of `key`.
  void serve(Lru& cache, const std::string& key, const std::string& content_type, Respond respond,
             std::function<Response()> make);

  boost::asio::io_context& io_;
  boost::asio::thread_pool& pool_;
  Lru pngs_{32, {}};
  Lru paths_{16, {}};
  std::map<std::string, std::vector<Respond>> waiting_;  // key -> requests for a picture being made
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace cncstream::daemon
