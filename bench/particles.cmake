# Seed 003 particles vs CGAL's implicit surface mesher, VTK's marching cubes and marching
# tetrahedra (docs/benchmarks.md). VTK comes with libpcl-dev (libvtk9-dev).
find_package(VTK REQUIRED COMPONENTS CommonCore CommonDataModel FiltersCore)
add_executable(bench_particles ${CMAKE_CURRENT_LIST_DIR}/bench_particles.cpp)
target_link_libraries(bench_particles PRIVATE scanmesh::meshing scanmesh::sim
  scanmesh::acquisition scanmesh::reconstruction CGAL::CGAL
  OpenMP::OpenMP_CXX VTK::CommonCore VTK::CommonDataModel VTK::FiltersCore)
target_include_directories(bench_particles PRIVATE ${PROJECT_SOURCE_DIR}/apps/src)
