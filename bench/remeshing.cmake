# Seed 001 remeshing against CGAL Polygon_mesh_processing::isotropic_remeshing on the simulated
# head's grid mesh, same input, same vertex count, same constrained edges; plus the non-manifold
# two-box input that CGAL's halfedge mesh cannot hold (docs/remeshing.md, "Benchmark").
add_executable(bench_remeshing ${CMAKE_CURRENT_LIST_DIR}/bench_remeshing.cpp)
target_link_libraries(bench_remeshing PRIVATE scanmesh::sim scanmesh::acquisition
  scanmesh::meshing CGAL::CGAL OpenMP::OpenMP_CXX)
