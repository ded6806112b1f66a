// Running the real programs for client tests: build/bin/isomesh and isomesh-load as a person
// would (arguments, exit status, output), against a real build/bin/isomesh-server started on a
// free loopback port.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

#include "mesh/mesh.h"

namespace isomesh::testing {

/// A program of this build: ISOMESH_BINARY_DIR/bin/NAME.
std::string binary(const std::string& name);

struct ProgramRun {
    int status = -1;  ///< exit status; -1 if it did not exit normally
    std::string out;
    std::string err;
};

/// Runs `program` with `args` (no shell) to completion, capturing stdout and stderr.
ProgramRun run_program(const std::string& program, const std::vector<std::string>& args);

/// isomesh-server on 127.0.0.1 and a port it chose, for the lifetime of this object; stopped
/// with SIGTERM (and SIGKILL if it does not drain in 10 s).
class ServerProcess {
  public:
    /// Starts the server with `extra_args` (two workers unless they give --threads) and waits (at
    /// most 20 s) for its "listening" log line. Check ok() afterwards; log() tells what went wrong.
    explicit ServerProcess(const std::vector<std::string>& extra_args = {});
    ~ServerProcess();
    ServerProcess(const ServerProcess&) = delete;
    ServerProcess& operator=(const ServerProcess&) = delete;

    bool ok() const { return port_ != 0; }
    int port() const { return port_; }
    std::string ws_url() const;
    const std::string& log() const { return log_; }

  private:
    pid_t pid_ = -1;
    int log_fd_ = -1;
    int port_ = 0;
    std::string log_;
};

/// A binary little-endian PLY as core's mesh_io writes it (float x y z [nx ny nz], uchar-int
/// faces). Fails the current test and returns an empty mesh for anything else.
Mesh read_ply(const std::string& path);

}  // namespace isomesh::testing
