# Cross-builds the 32-bit Windows DLL (x86) and the C tests with mingw-w64; ctest runs the tests under Wine.
set(OPCCOMN_MINGW_TRIPLET i686-w64-mingw32)
set(CMAKE_SYSTEM_PROCESSOR x86)
include("${CMAKE_CURRENT_LIST_DIR}/mingw-w64-common.cmake")
