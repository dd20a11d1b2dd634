# pybind11 for Debian's /usr/bin/python3 (the interpreter with numpy and python3-vtk9), as the Python modules
# (python/, vtk/) build against it. A macro, so that Python's and pybind11's targets are the caller's; sets
# UVR_PYBIND11_FOUND.
macro(uvr_find_pybind11)
  set(PYBIND11_FINDPYTHON ON)
  if(EXISTS /usr/bin/python3 AND NOT Python_EXECUTABLE)
    set(Python_EXECUTABLE /usr/bin/python3)
  endif()
  find_package(Python COMPONENTS Interpreter Development.Module QUIET)
  find_package(pybind11 CONFIG QUIET)
  if(pybind11_FOUND AND Python_FOUND)
    set(UVR_PYBIND11_FOUND ON)
  else()
    set(UVR_PYBIND11_FOUND OFF)
  endif()
endmacro()
