# The real-data corpus (docs/testing.md, "Real-data corpus"): scanned point sets and scanned
# meshes from Debian 12's libcgal-demo (its data.tar.gz), unpacked at configure time into
# ${SCANMESH_CORPUS_DIR}. Tests and benchmarks read them from there; nothing is downloaded.
# scripts/install-deps installs libcgal-demo with the test dependencies (never a run-time need).
set(SCANMESH_CGAL_DATA_TARBALL /usr/share/doc/libcgal-demo/data.tar.gz CACHE FILEPATH
    "libcgal-demo's data.tar.gz (the real-data corpus)")
set(SCANMESH_CORPUS_DIR ${PROJECT_BINARY_DIR}/corpus)
# The members the tests and bench_real use (sizes and origins in docs/testing.md).
set(scanmesh_corpus_clouds kitten.xyz hippo1.ply hippo2.ply oni.ply radar.xyz)
set(scanmesh_corpus_meshes nefertiti.off head.off elephant.off lion-head.off mannequin-devil.off)
set(scanmesh_corpus_members)
foreach(f ${scanmesh_corpus_clouds})
  list(APPEND scanmesh_corpus_members data/points_3/${f})
endforeach()
foreach(f ${scanmesh_corpus_meshes})
  list(APPEND scanmesh_corpus_members data/meshes/${f})
endforeach()

set(scanmesh_corpus_complete TRUE)
foreach(m ${scanmesh_corpus_members})
  if(NOT EXISTS ${SCANMESH_CORPUS_DIR}/${m})
    set(scanmesh_corpus_complete FALSE)
  endif()
endforeach()
if(NOT scanmesh_corpus_complete)
  if(NOT EXISTS ${SCANMESH_CGAL_DATA_TARBALL})
    message(FATAL_ERROR "The real-data corpus needs ${SCANMESH_CGAL_DATA_TARBALL} "
            "(Debian package libcgal-demo; ./scripts/install-deps installs it)")
  endif()
  file(MAKE_DIRECTORY ${SCANMESH_CORPUS_DIR})
  execute_process(COMMAND tar -xzf ${SCANMESH_CGAL_DATA_TARBALL} -C ${SCANMESH_CORPUS_DIR}
                          ${scanmesh_corpus_members}
                  RESULT_VARIABLE scanmesh_corpus_rc ERROR_VARIABLE scanmesh_corpus_err)
  if(NOT scanmesh_corpus_rc EQUAL 0)
    message(FATAL_ERROR "Unpacking the real-data corpus failed: ${scanmesh_corpus_err}")
  endif()
endif()
message(STATUS "Real-data corpus: ${SCANMESH_CORPUS_DIR}/data")
