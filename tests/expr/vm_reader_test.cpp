// read_vm on Fidget's models in ../shared/testdata/vm and on malformed programs.
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>

#include "expr/vm_reader.h"
#include "support/shared_data.h"
#include "tape/op_math.h"
#include "tape_interpreter.h"

namespace isomesh {
namespace {

using testing::interpret;

std::string read_model(const std::string& name) {
    std::ifstream file(std::string(ISOMESH_SHARED_DIR "/testdata/vm/") + name);
    EXPECT_TRUE(file) << name;
    std::ostringstream text;
    text << file.rdbuf();
    return text.str();
}

Tape read_model_tape(const std::string& name) {
    CompileResult result = read_vm(read_model(name));
    EXPECT_TRUE(result.ok()) << name << ": " << (result.error ? result.error->to_string() : "");
    EXPECT_EQ(result.tape.validate(), "");
    return result.tape;
}

TEST(ReadVm, tanglecube_agrees_with_its_formula) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    Tape tape = read_model_tape("tanglecube.vm");
    EXPECT_EQ(tape.size(), 20u);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
    for (int i = 0; i < 200; ++i) {
        double x = coordinate(random), y = coordinate(random), z = coordinate(random);
        double expected = std::pow(x, 4) - 5 * x * x + std::pow(y, 4) - 5 * y * y + std::pow(z, 4) -
                          5 * z * z + 10;
        EXPECT_NEAR(interpret(tape, x, y, z), expected, 1e-9 * (1 + std::abs(expected)));
    }
}

TEST(ReadVm, reads_the_large_models) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    // Instruction counts from the README; sharing repeated constants may only shorten them.
    const std::tuple<std::string, std::size_t, unsigned> models[] = {
        {"bear.vm", 657, 7u}, {"colonnade.vm", 808, 7u}, {"prospero.vm", 7866, 3u}};
    for (const auto& [name, instructions, variables] : models) {
        Tape tape = read_model_tape(name);
        EXPECT_LE(tape.size(), instructions) << name;
        EXPECT_GE(tape.size(), instructions * 8 / 10) << name;
        EXPECT_EQ(tape.variables_used(), variables) << name;
        EXPECT_TRUE(tape.params.empty());
        EXPECT_TRUE(std::isfinite(interpret(tape, 0.1, 0.2, 0.3))) << name;
    }
}

/// The .vm program `text` run line by line on doubles at (x, y, z), as Fidget would: no tape, no
/// folding, no fusion (the scalar semantics of op_math.h; recip and two-operand atan).
double run_vm_text(const std::string& text, double x, double y, double z) {
    std::map<std::string, double> values;
    std::istringstream lines(text);
    std::string line;
    double last = 0.0;
    while (std::getline(lines, line)) {
        std::istringstream words(line.substr(0, line.find('#')));
        std::string name, opcode, a, b;
        if (!(words >> name >> opcode)) continue;
        words >> a >> b;
        if (opcode == "var-x" || opcode == "var-y" || opcode == "var-z") {
            last = opcode == "var-x" ? x : opcode == "var-y" ? y : z;
        } else if (opcode == "const") {
            last = std::stod(a);
        } else if (opcode == "recip") {
            last = 1.0 / values.at(a);
        } else {
            int k = static_cast<int>(Op::Neg);
            while (op_name(static_cast<Op>(k)) != opcode) ++k;
            const Op op = opcode == "atan" && !b.empty() ? Op::Atan2 : static_cast<Op>(k);
            last = b.empty() ? apply_unary(op, values.at(a), 0.0)
                             : apply_binary(op, values.at(a), values.at(b));
        }
        values[name] = last;
    }
    return last;
}

// bear's smooth blends, ln(exp(-k a) + exp(-k b)) written out in the file, load as logsumexp, its
// distances as hypot, and the model's values stay those of the file run line by line, within a few
// rounding errors of the unit scale (values near the surface are near 0: relative errors mean
// nothing there).
TEST(ReadVm, bear_blends_and_distances_load_fused_with_the_same_values) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    const std::string text = read_model("bear.vm");
    Tape tape = read_model_tape("bear.vm");
    EXPECT_EQ(testing::count_ops(tape, Op::LogSumExp), 8);
    EXPECT_EQ(testing::count_ops(tape, Op::Ln), 0);
    // Its 23 distances sqrt(a^2 + b^2 + c^2) load as two hypots each.
    EXPECT_EQ(testing::count_ops(tape, Op::Hypot), 46);
    EXPECT_EQ(testing::count_ops(tape, Op::Sqrt), 0);
    std::mt19937 random(9);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    double worst = 0.0;
    for (int i = 0; i < 500; ++i) {
        double x = coordinate(random), y = coordinate(random), z = coordinate(random);
        double expected = run_vm_text(text, x, y, z);
        double error =
            std::abs(interpret(tape, x, y, z) - expected) / std::max(1.0, std::abs(expected));
        worst = std::max(worst, error);
    }
    EXPECT_LE(worst, 16 * std::numeric_limits<double>::epsilon());  // 2.4 measured
}

TEST(ReadVm, accepts_comments_blank_lines_and_fidget_opcodes) {
    CompileResult result = read_vm(
        "# a comment\n\n_x var-x   # trailing comment\r\n_y var-y\n_a atan _y _x\n"
        "_r recip _a\n_c const +2.5\n_o pow _r _c\n");
    ASSERT_TRUE(result.ok()) << result.error->to_string();
    double x = 0.7, y = 0.4;
    EXPECT_DOUBLE_EQ(interpret(result.tape, x, y, 0), std::pow(1 / std::atan2(y, x), 2.5));
}

struct VmErrorCase {
    std::string text;
    std::string message;
    int line;
    int column;
};

TEST(ReadVm, errors_name_problem_line_and_column) {
    const VmErrorCase cases[] = {
        {"", "no instructions", 0, 0},
        {"# only a comment\n\n", "no instructions", 2, 0},
        {"_x var-x\n_y frobnicate _x\n", "unknown opcode 'frobnicate'", 2, 4},
        {"_x var-x\n_y add _x _z\n", "undefined name '_z'", 2, 11},
        {"_x add _x _x\n", "undefined name '_x'", 1, 8},
        {"_x var-x\n_x var-y\n", "'_x' already defined at line 1", 2, 1},
        {"_x var-x\n_y add _x\n", "'add' takes 2 operands, got 1", 2, 4},
        {"_x var-x\n_y neg _x _x\n", "'neg' takes 1 operand, got 2", 2, 4},
        {"_x var-x 3\n", "'var-x' takes 0 operands, got 1", 1, 4},
        {"_c const\n", "'const' takes 1 operand, got 0", 1, 4},
        {"_c const 2.5x\n", "bad number '2.5x'", 1, 10},
        {"_c const nan\n", "bad number 'nan'", 1, 10},
        {"_c const inf\n", "bad number 'inf'", 1, 10},
        {"_c const 1e999\n", "bad number '1e999'", 1, 10},
        {"  _lonely\n", "missing opcode after '_lonely'", 1, 3},
        {"_x var-x\n_y powi _x\n", "unknown opcode 'powi'", 2, 4},
        {"_x var-x\n_y logsumexp _x _x\n", "unknown opcode 'logsumexp'", 2, 4},
    };
    for (const VmErrorCase& c : cases) {
        CompileResult result = read_vm(c.text);
        ASSERT_FALSE(result.ok()) << c.text;
        EXPECT_EQ(result.error->message, c.message) << c.text;
        EXPECT_EQ(result.error->line, c.line) << c.text;
        EXPECT_EQ(result.error->column, c.column) << c.text;
    }
    EXPECT_EQ(read_vm("_x var-x\n_y frobnicate _x\n").error->to_string(),
              "unknown opcode 'frobnicate' at line 2, column 4");
}

TEST(ReadVm, limits_apply) {
    CompileLimits limits;
    limits.max_instructions = 2;
    EXPECT_TRUE(read_vm("_x var-x\n_y neg _x\n", limits).ok());
    CompileResult result = read_vm("_x var-x\n_y neg _x\n_z neg _y\n", limits);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error->to_string(), "more than 2 instructions at line 3");
    limits.max_vm_bytes = 8;
    EXPECT_EQ(read_vm("_x var-x\n", limits).error->message,
              "file too large: 9 bytes, the limit is 8");
}

}  // namespace
}  // namespace isomesh
