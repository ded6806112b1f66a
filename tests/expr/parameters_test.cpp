#include <gtest/gtest.h>

#include <cmath>

#include "expr/compile.h"
#include "expr/parameters.h"
#include "tape_interpreter.h"

namespace isomesh {
namespace {

using testing::interpret;

TEST(BindParameters, values_follow_tape_order) {
    Tape tape = compile_expression("b x + a = c").tape;
    ASSERT_EQ(tape.params, (std::vector<std::string>{"b", "a", "c"}));
    ParameterBinding binding = bind_parameters(tape, {{"a", 1.0}, {"b", 2.0}, {"c", 3.0}});
    ASSERT_TRUE(binding.ok());
    EXPECT_EQ(binding.values, (std::vector<double>{2.0, 1.0, 3.0}));
    EXPECT_FALSE(binding.warning);
}

TEST(BindParameters, compile_once_bind_many_times) {
    Tape tape = compile_expression("x^2 + y^2 + z^2 = r^2").tape;
    for (double r : {0.5, 1.0, 2.0}) {
        ParameterBinding binding = bind_parameters(tape, {{"r", r}});
        ASSERT_TRUE(binding.ok());
        EXPECT_DOUBLE_EQ(interpret(tape, r, 0, 0, binding.values), 0.0);
    }
}

TEST(BindParameters, missing_values_are_all_listed) {
    Tape tape = compile_expression("a x + b y + c z").tape;
    ParameterBinding binding = bind_parameters(tape, {{"b", 1.0}});
    ASSERT_FALSE(binding.ok());
    EXPECT_EQ(*binding.error, "no value for parameters 'a', 'c'");
    EXPECT_EQ(binding.missing, (std::vector<std::string>{"a", "c"}));
    EXPECT_EQ(*bind_parameters(tape, {{"a", 1.0}, {"c", 2.0}}).error, "no value for parameter 'b'");
}

TEST(BindParameters, unused_names_are_a_warning) {
    Tape tape = compile_expression("a x").tape;
    ParameterBinding binding = bind_parameters(tape, {{"a", 1.0}, {"zeta", 2.0}, {"b", 3.0}});
    EXPECT_TRUE(binding.ok());
    EXPECT_EQ(*binding.warning, "unused parameters 'b', 'zeta'");
    EXPECT_EQ(binding.unused, (std::vector<std::string>{"b", "zeta"}));
}

TEST(BindParameters, non_finite_values_are_errors) {
    Tape tape = compile_expression("a x + b").tape;
    ParameterBinding binding = bind_parameters(tape, {{"a", std::nan("")}});
    ASSERT_FALSE(binding.ok());
    EXPECT_EQ(*binding.error, "no value for parameter 'b'; non-finite value for parameter 'a'");
}

TEST(BindParameters, tape_without_parameters_binds_nothing) {
    ParameterBinding binding = bind_parameters(compile_expression("x").tape, {});
    EXPECT_TRUE(binding.ok());
    EXPECT_TRUE(binding.values.empty());
}

}  // namespace
}  // namespace isomesh
