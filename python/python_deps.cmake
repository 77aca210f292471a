# What the Python bindings need (python/CMakeLists.txt, docs/python.md), looked for quietly so that
# the top-level CMakeLists.txt can default SCANMESH_BUILD_PYTHON (to SCANMESH_PYTHON_DEFAULT) to
# whether it is all there.
#
# numpy and pybind11 come from Debian packages (python3-numpy, pybind11-dev), which serve
# Debian's own interpreter: default to /usr/bin/python3 even when another python3 (pyenv) comes
# first on PATH. -DPython3_EXECUTABLE=... still chooses another one.
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH
      "Python interpreter the scanmesh module is built for and tested with")
endif()
find_package(Python3 3.8 QUIET COMPONENTS Interpreter Development.Module NumPy)
# Python3 found first: pybind11's config then uses FindPython's Python3 (its "new" mode).
if(Python3_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
if(SCANMESH_SANITIZE OR SCANMESH_FUZZ)
  # An extension built with ASan cannot be loaded by an uninstrumented python3 (the ASan runtime
  # must come first), so the sanitizer tree (scripts/sanitize-tree) leaves the module out.
  set(SCANMESH_PYTHON_DEFAULT OFF)
  message(STATUS "scanmesh: Python bindings off by default in a sanitizer build")
elseif(Python3_FOUND AND pybind11_FOUND)
  set(SCANMESH_PYTHON_DEFAULT ON)
else()
  set(SCANMESH_PYTHON_DEFAULT OFF)
  message(STATUS "scanmesh: Python bindings off (they need Python 3 with its development "
                 "headers and NumPy, and pybind11: apt-get install python3-dev python3-numpy "
                 "pybind11-dev)")
endif()
