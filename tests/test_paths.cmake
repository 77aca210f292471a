# SCANMESH_SOURCE_DIR, SCANMESH_BINARY_DIR and SCANMESH_CORPUS_DIR for tests and benchmarks
# (tests/scanmesh_test_paths.h) call functions of one source generated per build folder, so that
# no other source has a path of the checkout in its compile command and a clone in another
# folder still hits the compiler cache (docs/testing.md).
configure_file(${CMAKE_CURRENT_LIST_DIR}/scanmesh_test_paths.cpp.in
               ${PROJECT_BINARY_DIR}/tests/scanmesh_test_paths.cpp @ONLY)
add_library(scanmesh_test_paths STATIC ${PROJECT_BINARY_DIR}/tests/scanmesh_test_paths.cpp)
target_include_directories(scanmesh_test_paths PUBLIC ${CMAKE_CURRENT_LIST_DIR})
