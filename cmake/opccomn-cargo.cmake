# Runs cargo for the CMake build and keeps what rustc reports the static library needs besides itself.
#
#   cmake -DSTATIC_LIBS=<file> -P opccomn-cargo.cmake -- cargo rustc --lib ... -- --print native-static-libs
#
# Runs the command after the first `--`, shows its output, and writes the libraries of rustc's
# `note: native-static-libs: ...` line to STATIC_LIBS as rustc printed them (one line: `-lkernel32
# -lntdll ...` for GNU targets, `kernel32.lib ntdll.lib ...` for MSVC). Cargo repeats the note when the
# library is already up to date, so the file is written on every run. Fails when cargo fails or
# rustc reported no such line. The pkg-config file, the CMake packages and the documentation take the
# list from there (docs/windows.md, "Static linking").
if(NOT STATIC_LIBS)
  message(FATAL_ERROR "opccomn-cargo.cmake: STATIC_LIBS is not set")
endif()
set(_command "")
set(_in_command FALSE)
math(EXPR _last "${CMAKE_ARGC} - 1")
foreach(_i RANGE ${_last})
  if(_in_command)
    list(APPEND _command "${CMAKE_ARGV${_i}}")
  elseif("${CMAKE_ARGV${_i}}" STREQUAL "--")
    set(_in_command TRUE)
  endif()
endforeach()
if(NOT _command)
  message(FATAL_ERROR "opccomn-cargo.cmake: no command after --")
endif()

if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.18)
  execute_process(COMMAND ${_command} RESULT_VARIABLE _rc ERROR_VARIABLE _err ECHO_ERROR_VARIABLE)
else()
  execute_process(COMMAND ${_command} RESULT_VARIABLE _rc ERROR_VARIABLE _err)
  message("${_err}")
endif()
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "cargo failed (${_rc})")
endif()
string(REGEX MATCHALL "native-static-libs: [^\r\n]*" _notes "${_err}")
if(NOT _notes)
  message(FATAL_ERROR "opccomn-cargo.cmake: rustc reported no native-static-libs (is `-- --print native-static-libs` on the command?)")
endif()
list(GET _notes -1 _note)
string(REGEX REPLACE "^native-static-libs: " "" _libs "${_note}")
string(STRIP "${_libs}" _libs)
file(WRITE "${STATIC_LIBS}" "${_libs}\n")
