# scanmesh as an installable CMake package (docs/library.md). Included from the top-level
# CMakeLists.txt after the module directories. `cmake --install <build> --prefix <dir>` puts
#   bin/scanmesh
#   lib/libscanmesh_<component>.so*          (or .a with SCANMESH_SHARED_LIBS=OFF)
#   include/scanmesh/<component>/...
#   lib/cmake/scanmesh/scanmeshConfig.cmake, scanmeshConfigVersion.cmake,
#                      scanmesh-<component>-targets*.cmake   (one export set per component)
# and a consumer writes find_package(scanmesh REQUIRED COMPONENTS core meshing) and links
# scanmesh::core, scanmesh::meshing. (lib is CMAKE_INSTALL_LIBDIR: lib/<multiarch> for /usr.)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# The components: every module library made by scanmesh_module_library, in dependency order
# (docs/ARCHITECTURE.md). The inter-component and third-party dependencies a consumer needs are
# in scanmeshConfig.cmake.in; tests/install checks them by building a consumer against an
# installed tree.
get_property(SCANMESH_COMPONENTS GLOBAL PROPERTY SCANMESH_COMPONENTS)
set(scanmesh_config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/scanmesh)

foreach(component IN LISTS SCANMESH_COMPONENTS)
  set(target scanmesh_${component})
  # EXPORT_NAME: installed as scanmesh::<component>, the same name as the in-tree alias.
  # SOVERSION major.minor: before 1.0 a minor release may break the ABI (and the package version
  # check below accepts the same major.minor only).
  # INSTALL_RPATH $ORIGIN: a library finds its sibling libraries wherever the tree is installed
  # (RUNPATH is not inherited from the executable). The build tree keeps CMake's absolute
  # build RPATHs, so tests and build/apps/scanmesh run without installing.
  # DEFINE_SYMBOL "": no scanmesh_<component>_EXPORTS macro (nothing uses it), so objects compile
  # identically for shared and static libraries and switching reuses the compiler cache.
  set_target_properties(${target} PROPERTIES
    EXPORT_NAME ${component}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN"
    DEFINE_SYMBOL "")
  # The public headers use C++20 (std::span): consumers compile with at least that.
  target_compile_features(${target} PUBLIC cxx_std_20)
  # With -fPIC GCC assumes any exported function may be interposed at load time and stops inlining
  # calls between functions of one library; nothing here relies on interposition (clang already
  # behaves like this).
  target_compile_options(${target} PRIVATE
    $<$<CXX_COMPILER_ID:GNU>:-fno-semantic-interposition>)
  # Every library must name all it links against (a missing link fails here, not in a consumer).
  # Not with the sanitizers: clang leaves the sanitizer runtime symbols to the executable.
  if(SCANMESH_SHARED_LIBS AND NOT (SCANMESH_SANITIZE OR SCANMESH_FUZZ))
    target_link_options(${target} PRIVATE LINKER:--no-undefined)
  endif()

  install(TARGETS ${target} EXPORT scanmesh-${component}-targets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${component}/include/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.h")
  install(EXPORT scanmesh-${component}-targets
    FILE scanmesh-${component}-targets.cmake
    NAMESPACE scanmesh::
    DESTINATION ${scanmesh_config_dir})
endforeach()

# The CLI. It finds the libraries relative to itself (bin/../lib), so the tree can be moved.
file(RELATIVE_PATH scanmesh_bin_to_lib
  ${CMAKE_INSTALL_FULL_BINDIR} ${CMAKE_INSTALL_FULL_LIBDIR})
set_target_properties(scanmesh PROPERTIES INSTALL_RPATH "$ORIGIN/${scanmesh_bin_to_lib}")
install(TARGETS scanmesh RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/scanmeshConfig.cmake.in
  ${PROJECT_BINARY_DIR}/scanmeshConfig.cmake
  INSTALL_DESTINATION ${scanmesh_config_dir}
  NO_SET_AND_CHECK_MACRO)
# Before 1.0 every minor release may break the API: a request for 0.1 accepts 0.1.x only.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/scanmeshConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/scanmeshConfig.cmake
              ${PROJECT_BINARY_DIR}/scanmeshConfigVersion.cmake
  DESTINATION ${scanmesh_config_dir})
