// ConnectionManager, runtime part: connections made and removed while applications run
// (`rsca connect` / `rsca disconnect`), between ports of components of any running applications.
// A connection is checked before anything is made (both ports exist with the right direction,
// they carry the same port type), gets a topic of its own, and goes when either application is
// released (the other end is disconnected).
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "control/endpoint.hpp"
#include "domain/application.hpp"

namespace rsca::domain {

struct PortRef {
  std::string application;
  std::string component;
  std::string port;
  std::string to_string() const { return application + "/" + component + "." + port; }
};

struct RuntimeConnection {
  std::string id;
  PortRef uses;
  PortRef provides;
  std::string topic;
  std::string repid;
  nlohmann::json qos;
};

class ConnectionManager {
public:
  using FindApplication = std::function<std::shared_ptr<const Application>(const std::string &)>;

  ConnectionManager(std::string domain, control::Endpoint *endpoint, FindApplication find,
                    std::chrono::milliseconds timeout)
      : domain_(std::move(domain)), endpoint_(endpoint), find_(std::move(find)), timeout_(timeout) {
  }

  // Connects uses → provides with `qos` (SAD <qos> names, defaults filled in); `id` may be empty.
  control::CallResult<RuntimeConnection> connect(const PortRef &uses, const PortRef &provides,
                                                 std::string id, const nlohmann::json &qos);
  control::CallResult<void> disconnect(const std::string &id);
  // `application` is being released: the other ends of its runtime connections are disconnected.
  void application_released(const std::string &application);
  std::vector<RuntimeConnection> list() const;

private:
  control::CallResult<std::string> address_and_repid(const PortRef &ref, bool uses,
                                                     std::string &repid) const;

  std::string domain_;
  control::Endpoint *endpoint_;
  FindApplication find_;
  std::chrono::milliseconds timeout_;
  mutable std::mutex mutex_;
  std::map<std::string, RuntimeConnection> connections_;
  std::uint64_t next_ = 0;
};

nlohmann::json to_json(const RuntimeConnection &connection);

} // namespace rsca::domain
