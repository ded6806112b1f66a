#include "client_processes.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

extern char** environ;

namespace isomesh::testing {
namespace {

using namespace std::chrono_literals;

std::string read_file(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    return text.str();
}

/// A fresh file name in the temporary directory.
std::string scratch_path(const std::string& what) {
    static int counter = 0;
    return (std::filesystem::temp_directory_path() /
            ("isomesh_clients_test_" + std::to_string(::getpid()) + "_" +
             std::to_string(counter++) + "_" + what))
        .string();
}

/// Spawns `program` with stdout and stderr sent to the given files ("" = /dev/null).
pid_t spawn(const std::string& program, const std::vector<std::string>& args,
            const std::string& out_path, const std::string& err_path) {
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(program.c_str()));
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    const int flags = O_WRONLY | O_CREAT | O_TRUNC;
    posix_spawn_file_actions_addopen(&actions, 1, out_path.empty() ? "/dev/null" : out_path.c_str(),
                                     flags, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.empty() ? "/dev/null" : err_path.c_str(),
                                     flags, 0644);
    pid_t pid = -1;
    const int error = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) {
        ADD_FAILURE() << "cannot start " << program << ": " << std::strerror(error);
        return -1;
    }
    return pid;
}

int wait_for(pid_t pid) {
    int raw = 0;
    if (::waitpid(pid, &raw, 0) != pid) return -1;
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
}

/// The port of a {"event":"listening","port":N,...} log line, or 0.
int listening_port(const std::string& line) {
    const auto entry = nlohmann::json::parse(line, nullptr, false);
    if (!entry.is_object() || entry.value("event", "") != "listening") return 0;
    return entry.value("port", 0);
}

}  // namespace

std::string binary(const std::string& name) {
    return std::string(ISOMESH_BINARY_DIR) + "/bin/" + name;
}

ProgramRun run_program(const std::string& program, const std::vector<std::string>& args) {
    const std::string out_path = scratch_path("out");
    const std::string err_path = scratch_path("err");
    ProgramRun run;
    const pid_t pid = spawn(program, args, out_path, err_path);
    if (pid > 0) run.status = wait_for(pid);
    run.out = read_file(out_path);
    run.err = read_file(err_path);
    std::filesystem::remove(out_path);
    std::filesystem::remove(err_path);
    return run;
}

ServerProcess::ServerProcess(const std::vector<std::string>& extra_args) {
    std::vector<std::string> args = {"--bind",      "127.0.0.1", "--port",  "0",
                                     "--log-level", "info",      "--store", "none"};
    if (std::find(extra_args.begin(), extra_args.end(), "--threads") == extra_args.end())
        args.insert(args.end(), {"--threads", "2"});
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    // The log goes to a file (a pipe nobody drains could fill up and block the server).
    const std::string log_path = scratch_path("server.log");
    pid_ = spawn(binary("isomesh-server"), args, "", log_path);
    if (pid_ <= 0) return;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (std::chrono::steady_clock::now() < deadline) {
        log_ = read_file(log_path);
        std::istringstream lines(log_);
        for (std::string line; std::getline(lines, line);) {
            if (int port = listening_port(line)) {
                port_ = port;
                std::filesystem::remove(log_path);
                return;
            }
        }
        if (::waitpid(pid_, nullptr, WNOHANG) == pid_) {
            pid_ = -1;
            break;
        }
        std::this_thread::sleep_for(20ms);
    }
    std::filesystem::remove(log_path);
}

ServerProcess::~ServerProcess() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (::waitpid(pid_, nullptr, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
            return;
        }
        std::this_thread::sleep_for(20ms);
    }
}

std::string ServerProcess::ws_url() const {
    return "ws://127.0.0.1:" + std::to_string(port_) + "/ws";
}

Mesh read_ply(const std::string& path) {
    const std::string bytes = read_file(path);
    const std::string end_marker = "end_header\n";
    const auto end = bytes.find(end_marker);
    if (end == std::string::npos) {
        ADD_FAILURE() << path << ": not a PLY file";
        return {};
    }
    std::istringstream header(bytes.substr(0, end));
    std::size_t vertices = 0, faces = 0, floats = 0;
    for (std::string word; header >> word;) {
        if (word == "element") {
            std::string name;
            header >> name >> (name == "vertex" ? vertices : faces);
        } else if (word == "float") {
            ++floats;
        }
    }
    const char* data = bytes.data() + end + end_marker.size();
    const std::size_t expected = vertices * floats * 4 + faces * 13;
    if (bytes.size() - (end + end_marker.size()) != expected || (floats != 3 && floats != 6)) {
        ADD_FAILURE() << path << ": unexpected PLY layout";
        return {};
    }
    Mesh mesh;
    for (std::size_t v = 0; v < vertices; ++v) {
        float values[6] = {};
        std::memcpy(values, data + v * floats * 4, floats * 4);
        mesh.positions.emplace_back(values[0], values[1], values[2]);
        if (floats == 6) mesh.normals.emplace_back(values[3], values[4], values[5]);
    }
    data += vertices * floats * 4;
    for (std::size_t f = 0; f < faces; ++f) {
        std::int32_t corners[3];
        std::memcpy(corners, data + f * 13 + 1, sizeof corners);
        mesh.triangles.push_back({static_cast<std::uint32_t>(corners[0]),
                                  static_cast<std::uint32_t>(corners[1]),
                                  static_cast<std::uint32_t>(corners[2])});
    }
    return mesh;
}

}  // namespace isomesh::testing
