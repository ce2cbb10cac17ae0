# Writes opccomn.pc from cmake/opccomn.pc.in at build time: its Libs.private are the libraries rustc
# reported for the static library (STATIC_LIBS, written by opccomn-cargo.cmake), in pkg-config's `-l`
# form (`kernel32.lib` becomes `-lkernel32`).
#
#   cmake -DIN=opccomn.pc.in -DOUT=opccomn.pc -DSTATIC_LIBS=<file> -DCMAKE_INSTALL_LIBDIR=lib
#         -DCMAKE_INSTALL_INCLUDEDIR=include -DOPCCOMN_VERSION_FULL=0.3.0-dev -P opccomn-pc.cmake
file(READ "${STATIC_LIBS}" _libs)
string(STRIP "${_libs}" _libs)
separate_arguments(_items UNIX_COMMAND "${_libs}")
set(_pc "")
foreach(_item IN LISTS _items)
  if(_item MATCHES "^([^-].*)\\.lib$")
    set(_item "-l${CMAKE_MATCH_1}")
  endif()
  string(APPEND _pc " ${_item}")
endforeach()
string(STRIP "${_pc}" OPCCOMN_PC_STATIC_LIBS)
configure_file("${IN}" "${OUT}" @ONLY)
