# Worst-case inputs of the hostile-input issue at growing sizes (docs/safety.md, "Findings";
# docs/benchmarks.md, "Hostile inputs"): runs the scanmesh binary, no library linked.
add_executable(bench_hostile ${CMAKE_CURRENT_LIST_DIR}/bench_hostile.cpp)
target_compile_definitions(bench_hostile PRIVATE SCANMESH_BINARY_DIR="${PROJECT_BINARY_DIR}"
  SCANMESH_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(bench_hostile scanmesh)
