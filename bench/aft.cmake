# Seed 000 animation meshes vs CGAL isotropic remeshing of the grid mesh (docs/animation-meshes.md).
add_executable(bench_aft ${CMAKE_CURRENT_LIST_DIR}/bench_aft.cpp
  ${CMAKE_CURRENT_LIST_DIR}/aft_traced_lines.cpp)
target_link_libraries(bench_aft PRIVATE scanmesh::meshing scanmesh::sim CGAL::CGAL
  OpenMP::OpenMP_CXX)  # omp_get_max_threads for the report
target_link_libraries(bench_aft PRIVATE scanmesh_test_paths)
