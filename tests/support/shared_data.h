// The shared test data (the Marching Cubes 33 suite, Fidget's .vm models) is not part of the
// repository: it lives in ISOMESH_SHARED_DIR (default ../shared beside the checkout; configure with
// -DISOMESH_SHARED_DIR=/path/to/shared). Without it, the tests that need it skip, saying so.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>

namespace isomesh::test {

/// The shared data's testdata/ folder exists.
inline bool shared_data_present() {
    return std::filesystem::is_directory(ISOMESH_SHARED_DIR "/testdata");
}

}  // namespace isomesh::test

/// The reason a test skips without the shared data.
#define ISOMESH_NO_SHARED_DATA \
    "no shared test data in " ISOMESH_SHARED_DIR " (configure with -DISOMESH_SHARED_DIR=...)"

/// Skips the current test (returning from it) when the shared data is absent.
#define ISOMESH_SKIP_WITHOUT_SHARED_DATA()                                                   \
    do {                                                                                     \
        if (!::isomesh::test::shared_data_present()) GTEST_SKIP() << ISOMESH_NO_SHARED_DATA; \
    } while (false)
