# Point-cloud fans (seed 002) against PCL GreedyProjectionTriangulation and CGAL's advancing
# front surface reconstruction, same clouds, same run (docs/benchmarks.md, "Point-cloud fans").
add_executable(bench_fans ${CMAKE_CURRENT_LIST_DIR}/bench_fans.cpp)
target_link_libraries(bench_fans PRIVATE scanmesh::sim scanmesh::meshing CGAL::CGAL
  pcl_common pcl_search pcl_kdtree pcl_surface OpenMP::OpenMP_CXX)
target_include_directories(bench_fans SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
