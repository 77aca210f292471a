# scanmesh_module_library(<module> <source>...): the library of one module (docs/ARCHITECTURE.md)
# as every module has it: scanmesh_<module>, shared or static as SCANMESH_LIBRARY_TYPE says, its
# alias scanmesh::<module>, the public headers under <module>/include and the project's warnings.
# The module's own CMakeLists.txt adds its links (target_link_libraries with PUBLIC / PRIVATE).
function(scanmesh_module_library module)
  add_library(scanmesh_${module} ${SCANMESH_LIBRARY_TYPE} ${ARGN})
  add_library(scanmesh::${module} ALIAS scanmesh_${module})
  target_include_directories(scanmesh_${module} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  target_link_libraries(scanmesh_${module} PRIVATE $<BUILD_INTERFACE:scanmesh_warnings>)
  # Every module is an installed component (cmake/ScanmeshPackage.cmake), in the order the
  # top-level CMakeLists.txt adds them: dependency order.
  set_property(GLOBAL APPEND PROPERTY SCANMESH_COMPONENTS ${module})
endfunction()
