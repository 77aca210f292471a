# Every stage against its anchor on the real-data corpus (tests/real_corpus.cmake), same input,
# same run (docs/benchmarks.md, "Real scans (bench_real)").
add_executable(bench_real ${CMAKE_CURRENT_LIST_DIR}/bench_real.cpp)
target_link_libraries(bench_real PRIVATE scanmesh::acquisition scanmesh::reconstruction
  scanmesh::meshing CGAL::CGAL pcl_common pcl_features pcl_search pcl_kdtree pcl_surface
  OpenMP::OpenMP_CXX)
target_include_directories(bench_real SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_link_libraries(bench_real PRIVATE scanmesh_test_paths)
