#pragma once
// The daemon's side of the shop (docs/shop.md): what the shop client may ask
// of this daemon (is a machine free, add a claimed job to its local queue,
// never started by itself), and the client itself. Built only when the
// configuration names a hub ([shop] url, --shop).
#include <boost/asio/io_context.hpp>

#include <memory>
#include <vector>

#include "cncstream/daemon/config.hpp"
#include "cncstream/shop/shdr_adapter.hpp"
#include "cncstream/shop/shop_client.hpp"
#include "cncstream/shop/shop_view.hpp"

namespace cncstream::daemon {

class FileStore;
class Machines;
class JobManager;

class ShopLink final : public shop::LocalJobs {
 public:
  ShopLink(boost::asio::io_context& io, const DaemonConfig& config, FileStore& files, Machines& machines,
           JobManager& jobs);
  ~ShopLink() override;
  bool free_for_shop_job(const std::string& machine) override;
  std::int64_t add_shop_job(const std::string& machine, const shop::ClaimedJob& job, std::int64_t earlier_local) override;
  void shop_job_cancelled(std::int64_t local_id) override;
  shop::ShopClient& client() { return *client_; }
  // The shop view's reads of the hub (a connection and a thread of their own).
  shop::ShopViewReader& view() { return *view_; }
  // The machine's MTConnect adapter's port (0: none).
  unsigned short mtconnect_port(const std::string& machine) const;

 private:
  FileStore& files_;
  Machines& machines_;
  JobManager& jobs_;
  std::vector<std::unique_ptr<shop::ShdrAdapter>> adapters_;
  std::unique_ptr<shop::ShopClient> client_;
  std::unique_ptr<shop::ShopViewReader> view_;
};

}  // namespace cncstream::daemon
