# Driver of the package tests (tests/install/CMakeLists.txt), run as cmake -P with -DSTEP=...:
#   install            cmake --install the build tree into PREFIX (a fresh folder), then check
#                      that every library, every public header, the package files and the
#                      scanmesh binary are there and that bin/scanmesh --help exits 0
#   consumer           configure (OpenCV, Ceres, PCL, ... disabled), build and run consumer/
#                      against PREFIX
#   unknown-component  configure unknown_component/ against PREFIX: must fail, with the message
# Any failed check is a FATAL_ERROR (the test fails) naming what was expected.
cmake_minimum_required(VERSION 3.25)

foreach(var STEP BUILD_DIR SOURCE_DIR PREFIX WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_install_test.cmake needs -D${var}=...")
  endif()
endforeach()
string(REPLACE "|" ";" COMPONENTS "${COMPONENTS}")
string(REPLACE "|" ";" LIBRARY_FILES "${LIBRARY_FILES}")
string(REPLACE "|" ";" DISABLED_PACKAGES "${DISABLED_PACKAGES}")

# Runs a command, prints its output, and returns its exit code and output.
function(run out_rc out_output)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  list(JOIN ARGN " " command)
  message(STATUS "$ ${command}\n${output}(exit ${rc})")
  set(${out_rc} "${rc}" PARENT_SCOPE)
  set(${out_output} "${output}" PARENT_SCOPE)
endfunction()

function(require_file path)
  if(NOT EXISTS "${path}")
    message(FATAL_ERROR "missing from the installed tree: ${path}")
  endif()
endfunction()

# A fresh configure of a project against the installed tree, with the compiler, launcher and
# (sanitizer) flags of the scanmesh build.
function(configure_project out_rc out_output source binary)
  file(REMOVE_RECURSE "${binary}")
  set(args -S "${source}" -B "${binary}" -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
      "-DCMAKE_PREFIX_PATH=${PREFIX}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
      "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}"
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF --no-warn-unused-cli)
  if(CXX_LAUNCHER)
    list(APPEND args "-DCMAKE_CXX_COMPILER_LAUNCHER=${CXX_LAUNCHER}")
  endif()
  run(rc output ${CMAKE_COMMAND} ${args} ${ARGN})
  set(${out_rc} "${rc}" PARENT_SCOPE)
  set(${out_output} "${output}" PARENT_SCOPE)
endfunction()

if(STEP STREQUAL "install")
  file(REMOVE_RECURSE "${PREFIX}")
  run(rc output ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}"
      --config ${BUILD_TYPE})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "cmake --install failed (is the whole tree built? cmake --build "
                        "${BUILD_DIR})")
  endif()

  foreach(file IN LISTS LIBRARY_FILES)
    require_file("${PREFIX}/${LIBDIR}/${file}")
  endforeach()
  foreach(file scanmeshConfig.cmake scanmeshConfigVersion.cmake)
    require_file("${PREFIX}/${LIBDIR}/cmake/scanmesh/${file}")
  endforeach()
  set(headers 0)
  foreach(component IN LISTS COMPONENTS)
    require_file("${PREFIX}/${LIBDIR}/cmake/scanmesh/scanmesh-${component}-targets.cmake")
    file(GLOB_RECURSE component_headers RELATIVE "${SOURCE_DIR}/${component}/include"
         "${SOURCE_DIR}/${component}/include/*.h")
    if(NOT component_headers)
      message(FATAL_ERROR "no headers found under ${SOURCE_DIR}/${component}/include")
    endif()
    foreach(header IN LISTS component_headers)
      require_file("${PREFIX}/${INCLUDEDIR}/${header}")
      math(EXPR headers "${headers} + 1")
    endforeach()
  endforeach()
  message(STATUS "installed: ${headers} headers, libraries ${LIBRARY_FILES}")

  set(binary "${PREFIX}/${BINDIR}/scanmesh")
  require_file("${binary}")
  run(rc output "${binary}" --help)
  if(NOT rc EQUAL 0 OR NOT output MATCHES "Usage: scanmesh")
    message(FATAL_ERROR "${binary} --help: exit ${rc}, expected 0 and a usage text")
  endif()
  # The installed binary must load the installed libraries (its RUNPATH), not the build tree's.
  if(SHARED)
    execute_process(COMMAND ldd "${binary}" OUTPUT_VARIABLE output RESULT_VARIABLE rc)
    file(REAL_PATH "${PREFIX}/${LIBDIR}" libdir)
    foreach(component IN LISTS COMPONENTS)
      string(REGEX MATCH "libscanmesh_${component}[^ ]* => ([^ ]+)" line "${output}")
      set(loaded "${CMAKE_MATCH_1}")
      if(loaded)
        file(REAL_PATH "${loaded}" loaded)
        get_filename_component(loaded_dir "${loaded}" DIRECTORY)
      endif()
      if(NOT loaded OR NOT loaded_dir STREQUAL libdir)
        message(FATAL_ERROR "${binary} loads libscanmesh_${component} from '${loaded}', "
                            "not from ${libdir} (ldd exit ${rc}):\n${output}")
      endif()
      message(STATUS "${binary} loads ${loaded}")
    endforeach()
  endif()

elseif(STEP STREQUAL "consumer")
  set(build "${WORK_DIR}/consumer-build")
  set(disabled)
  foreach(package IN LISTS DISABLED_PACKAGES)
    list(APPEND disabled -DCMAKE_DISABLE_FIND_PACKAGE_${package}=ON)
  endforeach()
  configure_project(rc output "${SOURCE_DIR}/tests/install/consumer" "${build}" ${disabled})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "configuring the consumer against ${PREFIX} failed")
  endif()
  # The package came from the installed tree.
  file(STRINGS "${build}/CMakeCache.txt" found_dir REGEX "^scanmesh_DIR:")
  string(FIND "${found_dir}" "=${PREFIX}/" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the consumer found scanmesh elsewhere: ${found_dir}")
  endif()
  run(rc output ${CMAKE_COMMAND} --build "${build}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "building the consumer failed")
  endif()
  run(rc output "${build}/scanmesh_consumer" "${WORK_DIR}/consumer-out")
  if(NOT rc EQUAL 0 OR NOT output MATCHES "consumer: all checks passed")
    message(FATAL_ERROR "the consumer failed (exit ${rc})")
  endif()

elseif(STEP STREQUAL "unknown-component")
  configure_project(rc output "${SOURCE_DIR}/tests/install/unknown_component"
                    "${WORK_DIR}/unknown-component-build")
  if(rc EQUAL 0)
    message(FATAL_ERROR "find_package(scanmesh COMPONENTS no_such_component) configured")
  endif()
  string(REGEX REPLACE "[ \n]+" " " output "${output}")  # CMake wraps the message
  if(NOT output MATCHES "unknown component 'no_such_component' \\(scanmesh has: core, ")
    message(FATAL_ERROR "configure failed, but without naming the unknown component")
  endif()

else()
  message(FATAL_ERROR "unknown STEP '${STEP}'")
endif()
