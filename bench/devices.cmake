# Capture loop and session writing in simulation (docs/benchmarks.md, "Devices and sessions").
add_executable(bench_devices ${CMAKE_CURRENT_LIST_DIR}/bench_devices.cpp)
target_link_libraries(bench_devices PRIVATE scanmesh::acquisition scanmesh::drivers scanmesh::sim)
