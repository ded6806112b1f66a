#include <gtest/gtest.h>

#include "expr/function_source.h"
#include "support/shared_data.h"

namespace isomesh {
namespace {

TEST(CompileSource, at_vm_path_reads_the_model) {
    ISOMESH_SKIP_WITHOUT_SHARED_DATA();
    CompileResult result = compile_source("@" ISOMESH_SHARED_DIR "/testdata/vm/tanglecube.vm");
    ASSERT_TRUE(result.ok()) << result.error->to_string();
    EXPECT_EQ(result.tape.size(), 20u);
}

TEST(CompileSource, plain_text_is_an_expression) {
    CompileResult result = compile_source("x^2 + y^2 = 1");
    ASSERT_TRUE(result.ok());
    EXPECT_EQ(result.tape.dump(), compile_expression("x^2 + y^2 = 1").tape.dump());
}

TEST(CompileSource, bad_files_are_errors) {
    CompileResult missing = compile_source("@/nonexistent/model.vm");
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.error->message,
              "cannot read '/nonexistent/model.vm': No such file or directory");
    CompileResult other = compile_source("@model.obj");
    ASSERT_FALSE(other.ok());
    EXPECT_EQ(other.error->message, "unsupported file 'model.obj': expected a .vm model");
    EXPECT_FALSE(compile_source("@" ISOMESH_SHARED_DIR "/testdata/vm/").ok());
}

}  // namespace
}  // namespace isomesh
