# Cross-compiles the engine, mocapctl and the tests for 64-bit Windows with MinGW-w64 (Debian's
# gcc-mingw-w64-x86-64, win32 threads), and runs the test executables under Wine:
#   cmake -S Packages/com.mocap.imu/Native~ -B build/windows \
#         -DCMAKE_TOOLCHAIN_FILE=Packages/com.mocap.imu/Native~/cmake/mingw-w64-x86_64.cmake
# (scripts/test_windows.sh does this and runs ctest).
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)

set(MOCAP_MINGW_PREFIX x86_64-w64-mingw32)
# The posix thread model (Debian's g++-mingw-w64-x86-64-posix): GoogleTest needs std::mutex and
# std::condition_variable, which GCC 12's win32 model lacks. The engine itself uses Win32 threads
# either way.
find_program(CMAKE_C_COMPILER NAMES ${MOCAP_MINGW_PREFIX}-gcc-posix REQUIRED)
find_program(CMAKE_CXX_COMPILER NAMES ${MOCAP_MINGW_PREFIX}-g++-posix REQUIRED)
find_program(CMAKE_RC_COMPILER NAMES ${MOCAP_MINGW_PREFIX}-windres)

set(CMAKE_FIND_ROOT_PATH /usr/${MOCAP_MINGW_PREFIX})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# The DLL and the executables must run with no MinGW runtime DLLs beside them (Unity loads
# mocap_imu.dll from the package's Plugins folder alone): the GCC and C++ runtimes and
# winpthreads are linked in statically.
# winpthreads included, should anything pull it in: -static takes every library's .a (the system
# DLLs' .a files are import libraries, so kernel32 & co. stay DLL imports).
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-static")

# Test executables (gtest discovery included) run under Wine; WINEPREFIX and WINEDEBUG come from
# the environment (scripts/test_windows.sh sets them).
find_program(MOCAP_WINE NAMES wine wine64)
if(MOCAP_WINE)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${MOCAP_WINE})
endif()
