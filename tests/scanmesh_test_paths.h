// Where this build's sources, binaries and real-data corpus are, for the tests that need them.
// Functions defined in one small generated source per build folder
// (tests/scanmesh_test_paths.cpp.in), not string macros: as -D flags on every test source the
// checkout's path was part of every compile command, and a clone in another folder (CI) missed
// the compiler cache for the whole test suite (docs/testing.md).
#pragma once

namespace scanmesh::test {
const char* source_dir();
const char* binary_dir();
const char* corpus_dir();
}  // namespace scanmesh::test

#define SCANMESH_SOURCE_DIR (::scanmesh::test::source_dir())
#define SCANMESH_BINARY_DIR (::scanmesh::test::binary_dir())
#define SCANMESH_CORPUS_DIR (::scanmesh::test::corpus_dir())
