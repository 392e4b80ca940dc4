// The local control channel of a running pipeline: a Unix socket private to
// the user (folder 0700, socket 0600), one JSON request and one JSON reply
// per connection. `plr swap` and `plr status` use it.
#pragma once

#include <plr/expected.hpp>

#include <nlohmann/json.hpp>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

namespace plr::kernel {

// $XDG_RUNTIME_DIR/plr, else $HOME/.local/state/plr: created 0700 and
// checked to be ours with that mode (refused otherwise).
Expected<std::string> control_dir();
// Refuses a pipeline name that is not a name (check_name).
Expected<std::string> control_socket_path(const std::string& pipeline);

class ControlServer {
 public:
  using Handler = std::function<nlohmann::json(const nlohmann::json& request)>;
  ControlServer(std::string path, Handler handler);
  ~ControlServer();
  Status start();

 private:
  void loop();

  std::string path_;
  Handler handler_;
  int fd_ = -1;
  int wake_[2] = {-1, -1};
  std::thread thread_;
};

Expected<nlohmann::json> control_request(const std::string& path, const nlohmann::json& request,
                                         int timeout_ms);

}  // namespace plr::kernel
