# Seed 003 particles vs CGAL's implicit surface mesher vs marching tetrahedra (docs/benchmarks.md).
add_executable(bench_particles ${CMAKE_CURRENT_LIST_DIR}/bench_particles.cpp)
target_link_libraries(bench_particles PRIVATE scanmesh::meshing scanmesh::sim CGAL::CGAL
  OpenMP::OpenMP_CXX)
target_include_directories(bench_particles PRIVATE ${PROJECT_SOURCE_DIR}/apps/src)
