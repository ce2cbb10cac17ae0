# ctest link.soname: the shared library's SONAME is SONAME (libopccomn.so.<major>), and PROGRAM, linked
# against it, records SONAME as what it needs, not the unversioned name or the build path.
# cmake -DOBJDUMP=objdump -DLIBRARY=libopccomn.so -DPROGRAM=prog -DSONAME=libopccomn.so.0 -P check-soname.cmake
foreach(_file IN ITEMS "${LIBRARY}" "${PROGRAM}")
  execute_process(COMMAND "${OBJDUMP}" -p "${_file}" OUTPUT_VARIABLE _dump RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${OBJDUMP} -p ${_file} failed (${_rc})")
  endif()
  if(_file STREQUAL "${LIBRARY}")
    set(_want "SONAME +${SONAME}\n")
  else()
    set(_want "NEEDED +${SONAME}\n")
  endif()
  if(NOT _dump MATCHES "${_want}")
    string(REGEX MATCHALL "(SONAME|NEEDED) +[^\n]*" _found "${_dump}")
    message(FATAL_ERROR "${_file}: expected '${_want}', found: ${_found}")
  endif()
  message(STATUS "${_file}: ${_want}")
endforeach()
