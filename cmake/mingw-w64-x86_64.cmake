# Cross-builds the Windows DLL (x64) and the C tests with mingw-w64; ctest runs the tests under Wine.
set(OPCCOMN_MINGW_TRIPLET x86_64-w64-mingw32)
set(CMAKE_SYSTEM_PROCESSOR x86_64)
include("${CMAKE_CURRENT_LIST_DIR}/mingw-w64-common.cmake")
