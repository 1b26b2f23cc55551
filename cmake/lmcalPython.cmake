# The Python interpreter the module is built for, tested with and installed into.
#
# Python3_EXECUTABLE (or Python_EXECUTABLE) given: that one. Otherwise the first that can
# import NumPy of: the active virtual environment's, the first python3 on PATH, and
# /usr/bin/python3 (Debian's, where python3-numpy installs). A python3 on PATH without NumPy
# (pyenv's, say) would build a module nobody can use with Debian's NumPy, so it is skipped.
function(lmcal_find_python out)
  if(Python_EXECUTABLE)
    set(${out} ${Python_EXECUTABLE} PARENT_SCOPE)
    return()
  endif()
  if(Python3_EXECUTABLE)
    set(${out} ${Python3_EXECUTABLE} PARENT_SCOPE)
    return()
  endif()
  set(candidates)
  if(DEFINED ENV{VIRTUAL_ENV})
    list(APPEND candidates "$ENV{VIRTUAL_ENV}/bin/python")
  endif()
  find_program(lmcal_path_python python3 NO_CACHE)
  if(lmcal_path_python)
    list(APPEND candidates ${lmcal_path_python})
  endif()
  list(APPEND candidates /usr/bin/python3)
  foreach(candidate IN LISTS candidates)
    if(EXISTS ${candidate})
      execute_process(COMMAND ${candidate} -c "import numpy" RESULT_VARIABLE failed OUTPUT_QUIET ERROR_QUIET)
      if(NOT failed)
        set(${out} ${candidate} PARENT_SCOPE)
        return()
      endif()
    endif()
  endforeach()
  set(${out} "" PARENT_SCOPE)
endfunction()

# Where `cmake --install` puts the package `lmcal`, relative to the install prefix: the
# interpreter's own platlib for its prefix (lib/python3.11/site-packages in a virtual
# environment; lib/python3.11/dist-packages for Debian's python3, which reads it under both
# /usr/local and /usr).
function(lmcal_python_install_dir python out)
  execute_process(
    COMMAND ${python} -c [=[
import os, sys, sysconfig
if sys.prefix == sys.base_prefix and "deb_system" in sysconfig.get_scheme_names():
    # Debian's own python3 reads PREFIX/lib/python3.X/dist-packages (/usr/local and /usr)
    print("lib/python%d.%d/dist-packages" % sys.version_info[:2])
else:
    paths = sysconfig.get_paths("posix_prefix", vars={"base": "/P", "platbase": "/P"})
    print(os.path.relpath(paths["platlib"], "/P"))
]=]
    OUTPUT_VARIABLE dir OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE failed)
  if(failed OR dir STREQUAL "")
    message(FATAL_ERROR "cannot ask ${python} for its site-packages folder; set LMCAL_PYTHON_INSTALL_DIR")
  endif()
  set(${out} ${dir} PARENT_SCOPE)
endfunction()
