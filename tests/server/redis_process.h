// A redis-server of the test's own (Debian's redis-server, installed by scripts/install-deps.sh)
// on a free loopback port, in memory only, stopped by the destructor: nothing is left running.
#pragma once

#include <sys/types.h>
#include <cstdint>
#include <string>

namespace isomesh::server::testing {

class RedisProcess {
  public:
    RedisProcess();
    ~RedisProcess();
    RedisProcess(const RedisProcess&) = delete;
    RedisProcess& operator=(const RedisProcess&) = delete;

    /// False when redis-server could not be started (why: error()).
    bool ok() const { return pid_ > 0; }
    const std::string& error() const { return error_; }
    std::uint16_t port() const { return port_; }

    /// Stops Redis (SIGTERM, waited for); start() brings a new, empty one up on the same port.
    void stop();
    bool start();

  private:
    pid_t pid_ = -1;
    std::uint16_t port_ = 0;
    std::string error_;
};

}  // namespace isomesh::server::testing
