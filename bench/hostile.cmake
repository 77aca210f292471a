# Worst-case inputs of the hostile-input issue at growing sizes (docs/safety.md, "Findings";
# docs/benchmarks.md, "Hostile inputs"): runs the scanmesh binary, no library linked.
add_executable(bench_hostile ${CMAKE_CURRENT_LIST_DIR}/bench_hostile.cpp)
target_link_libraries(bench_hostile PRIVATE scanmesh_test_paths)
add_dependencies(bench_hostile scanmesh)
