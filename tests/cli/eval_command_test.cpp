// `isomesh eval` end to end: runs build/bin/isomesh and checks its output and exit status.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/shared_data.h"

namespace {

struct CliRun {
    int status = -1;
    std::string out;
    std::string err;
};

std::string read_text(const std::filesystem::path& path) {
    std::ifstream file(path);
    std::ostringstream text;
    text << file.rdbuf();
    return text.str();
}

/// The parts one after the other. (Also keeps GCC 12's -Wrestrict false positive on
/// `"literal" + std::string` away.)
std::string joined(std::initializer_list<std::string_view> parts) {
    std::string text;
    for (std::string_view part : parts) text.append(part);
    return text;
}

/// Single-quotes an argument for /bin/sh.
std::string shell_quote(std::string_view arg) {
    std::string quoted = "'";
    for (char c : arg) {
        if (c == '\'') {
            quoted.append("'\\''");
        } else {
            quoted.push_back(c);
        }
    }
    quoted.push_back('\'');
    return quoted;
}

CliRun isomesh(std::initializer_list<std::string_view> args) {
    static int counter = 0;
    auto scratch =
        std::filesystem::temp_directory_path() /
        ("isomesh_cli_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::string out_path = scratch.string() + ".out";
    std::string err_path = scratch.string() + ".err";
    std::string command = shell_quote(std::string(ISOMESH_BINARY_DIR) + "/bin/isomesh");
    for (std::string_view arg : args) command.append(" ").append(shell_quote(arg));
    command.append(" >").append(shell_quote(out_path)).append(" 2>").append(shell_quote(err_path));
    int raw = std::system(command.c_str());
    CliRun run;
    run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    run.out = read_text(out_path);
    run.err = read_text(err_path);
    std::filesystem::remove(out_path);
    std::filesystem::remove(err_path);
    return run;
}

nlohmann::json single_json_line(const CliRun& run) {
    EXPECT_EQ(run.status, 0) << run.err;
    EXPECT_EQ(std::count(run.out.begin(), run.out.end(), '\n'), 1) << run.out;
    return nlohmann::json::parse(run.out);
}

TEST(EvalCommand, at_prints_value_and_gradient) {
    CliRun run = isomesh({"eval", "x^2+y^2+z^2=1", "--at", "1,2,3"});
    EXPECT_EQ(run.out, "{\"value\":13.0,\"gradient\":[2.0,4.0,6.0]}\n");
    nlohmann::json out = single_json_line(run);
    EXPECT_EQ(out["value"], 13.0);
}

TEST(EvalCommand, parameters_are_bound_by_name) {
    nlohmann::json out = single_json_line(isomesh(
        {"eval", "x^2 + y^2 + z^2 = r^2 + a", "--at", "1,0,0", "--param", "r=2", "--param=a=0.5"}));
    EXPECT_DOUBLE_EQ(out["value"].get<double>(), 1 - 4 - 0.5);
}

TEST(EvalCommand, expression_may_start_with_minus) {
    nlohmann::json out = single_json_line(isomesh({"eval", "-x^2", "--at", "-3,0,0"}));
    EXPECT_DOUBLE_EQ(out["value"].get<double>(), -9.0);
    EXPECT_DOUBLE_EQ(out["gradient"][0].get<double>(), 6.0);
}

TEST(EvalCommand, box_prints_interval_and_flags) {
    nlohmann::json sphere =
        single_json_line(isomesh({"eval", "x^2+y^2+z^2=1", "--box", "-1,2,0,0,0,0"}));
    EXPECT_LE(sphere["interval"][0].get<double>(), -1.0);
    EXPECT_GE(sphere["interval"][1].get<double>(), 3.0);
    EXPECT_FALSE(sphere["maybe_discontinuous"].get<bool>());
    EXPECT_FALSE(sphere["maybe_undefined"].get<bool>());
    nlohmann::json pole = single_json_line(isomesh({"eval", "1/x = 0", "--box", "-1,1,0,1,0,1"}));
    EXPECT_TRUE(pole["maybe_discontinuous"].get<bool>());
}

TEST(EvalCommand, reads_vm_files) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    std::string model = joined({"@", ISOMESH_SHARED_DIR, "/testdata/vm/tanglecube.vm"});
    nlohmann::json out = single_json_line(isomesh({"eval", model, "--at", "0,0,0"}));
    EXPECT_DOUBLE_EQ(out["value"].get<double>(), 10.0);
}

TEST(EvalCommand, compile_errors_exit_1_with_position) {
    CliRun run = isomesh({"eval", "x+1)", "--at", "0,0,0"});
    EXPECT_EQ(run.status, 1);
    EXPECT_TRUE(run.out.empty());
    EXPECT_EQ(run.err, "isomesh: unexpected ')' at column 4\n  x+1)\n     ^\n");
}

TEST(EvalCommand, vm_errors_name_file_and_line) {
    auto path = std::filesystem::temp_directory_path() /
                ("isomesh_cli_test_bad_" + std::to_string(::getpid()) + ".vm");
    std::ofstream(path) << "_x var-x\n_y frob _x\n";
    CliRun run = isomesh({"eval", joined({"@", path.string()}), "--at", "0,0,0"});
    std::filesystem::remove(path);
    EXPECT_EQ(run.status, 1);
    EXPECT_EQ(run.err, joined({"isomesh: ", path.string(),
                               ": unknown opcode 'frob' at line 2, column 4\n"}));
}

TEST(EvalCommand, missing_parameters_exit_1_and_unused_warn) {
    CliRun run = isomesh({"eval", "a x + b", "--at", "1,1,1", "--param", "c=1"});
    EXPECT_EQ(run.status, 1);
    EXPECT_NE(run.err.find("warning: unused parameter 'c'"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("no value for parameters 'a', 'b'"), std::string::npos) << run.err;
}

TEST(EvalCommand, usage_errors_exit_2) {
    for (auto args : {std::initializer_list<std::string_view>{"eval", "x"},
                      {"eval", "x", "--at", "1,2"},
                      {"eval", "x", "--at", "1,2,nan"},
                      {"eval", "x", "--at", "0,0,0", "--box", "0,1,0,1,0,1"},
                      {"eval", "x", "--box", "1,0,0,1,0,1"},
                      {"eval", "x", "--at", "0,0,0", "--param", "a"},
                      {"eval", "x", "--frobnicate", "1"},
                      {"frobnicate"},
                      {}}) {
        CliRun run = isomesh(args);
        EXPECT_EQ(run.status, 2) << run.err;
        EXPECT_FALSE(run.err.empty());
        EXPECT_TRUE(run.out.empty());
    }
}

TEST(EvalCommand, help_exits_0) {
    CliRun run = isomesh({"eval", "--help"});
    EXPECT_EQ(run.status, 0);
    EXPECT_NE(run.out.find("usage: isomesh eval"), std::string::npos);
    EXPECT_EQ(isomesh({"--help"}).status, 0);
}

}  // namespace
