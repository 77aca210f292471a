# Laser-line extraction against a Horus-like threshold + centre-of-mass extractor on the same
# frames, and the reconstruction time of a 400-step session (docs/acquisition.md, "Benchmarks").
add_executable(bench_vision ${CMAKE_CURRENT_LIST_DIR}/bench_vision.cpp)
target_link_libraries(bench_vision PRIVATE scanmesh::sim scanmesh::acquisition)
target_include_directories(bench_vision PRIVATE ${PROJECT_SOURCE_DIR}/apps/src)
