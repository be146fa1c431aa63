#!/usr/bin/env bash
# The engine on Windows for real: cross-compiles mocap_imu.dll, mocapctl.exe and the GoogleTest
# suites with MinGW-w64 (Native~/cmake/mingw-w64-x86_64.cmake) into build/windows/, then runs
# ctest with every test program under Wine (a throwaway prefix in build/windows/wine-prefix,
# headless) and the Windows ONNX Runtime DLLs of the same npm package as the Linux one
# (scripts/fetch_onnxruntime.sh puts them in build/third_party/onnxruntime/win-x64/).
#
# Not run on Windows (POSIX-only: tests/CMakeLists.txt and the #if !defined(_WIN32) blocks say
# why): the serial suites (a pseudo-terminal stands in for the port), mocapctl through a POSIX
# shell, oscdump, fork + RLIMIT_FSIZE disk-full tests, /proc/self/fd checks. Python-made inputs
# (the ONNX fixture models, the golden pose test's PyTorch side) run natively beside Wine.
#
# Prints ctest's output, ending with its summary ("100% tests passed, 0 tests failed out of N");
# exits non-zero when a test fails, when a test was skipped for anything but the HID transport
# (no hidapi exists for MinGW here), or when wine or MinGW-w64 is missing (a failure, not a skip).
# Usage: scripts/test_windows.sh [ctest arguments, e.g. -R UnicodePaths]
# Environment: MOCAP_WINDOWS_BUILD_DIR (default build/windows), JOBS (default: nproc).
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
NATIVE="$ROOT/Packages/com.mocap.imu/Native~"
BUILD="${MOCAP_WINDOWS_BUILD_DIR:-$ROOT/build/windows}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
LOG="$BUILD.ctest.log"

say() { echo "test_windows: $*"; }
die() { echo "test_windows: error: $*" >&2; exit 1; }
# Whatever stops this run (a missing tool, a failed build) must not leave the last run's results
# to be read as this one's.
rm -f "$LOG"

missing=()
for tool in x86_64-w64-mingw32-gcc-posix x86_64-w64-mingw32-g++-posix wine cmake /usr/bin/python3; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
[ -f /usr/src/googletest/CMakeLists.txt ] || missing+=("/usr/src/googletest (googletest)")
[ ${#missing[@]} -eq 0 ] || die "missing ${missing[*]}: run scripts/setup.sh (gcc-mingw-w64-x86-64-posix, g++-mingw-w64-x86-64-posix, wine64, googletest)"

"$ROOT/scripts/fetch_onnxruntime.sh" >/dev/null || die "could not fetch ONNX Runtime"
[ -f "$ROOT/build/third_party/onnxruntime/win-x64/onnxruntime.dll" ] \
  || die "build/third_party/onnxruntime/win-x64/onnxruntime.dll is missing after fetch_onnxruntime.sh"

started=$(date +%s)
mkdir -p "$BUILD"
say "configure + build (MinGW-w64) in $BUILD"
if ! cmake -S "$NATIVE" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
     -DCMAKE_TOOLCHAIN_FILE="$NATIVE/cmake/mingw-w64-x86_64.cmake" \
     -DMOCAP_WINE="$ROOT/scripts/wine_test_launcher.sh" >"$BUILD.configure.log" 2>&1; then
  cat "$BUILD.configure.log"; die "cmake configure failed"
fi
if ! cmake --build "$BUILD" -j"$JOBS" >"$BUILD.build.log" 2>&1; then
  tail -50 "$BUILD.build.log"; die "build failed (log: $BUILD.build.log)"
fi

# Nothing of MinGW's runtime may be needed beside the DLL (Unity loads it alone) or the programs.
for binary in "$BUILD/mocap_imu.dll" "$BUILD/mocapctl.exe"; do
  dlls=$(x86_64-w64-mingw32-objdump -p "$binary" | awk '/DLL Name:/ {print $3}' | tr '\n' ' ')
  for dll in $dlls; do
    case "${dll,,}" in kernel32.dll|msvcrt.dll|ws2_32.dll|shell32.dll) ;;
      *) die "$(basename "$binary") needs $dll (only Windows' own DLLs are allowed: link it statically)";; esac
  done
  say "$(basename "$binary") imports ${dlls% }"
done

# A prefix of our own, made once (the first wineboot takes a while); no display needed.
export WINEPREFIX="$BUILD/wine-prefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="
unset DISPLAY WAYLAND_DISPLAY
if [ ! -f "$WINEPREFIX/system.reg" ]; then
  say "creating the Wine prefix $WINEPREFIX"
  wineboot -i >"$BUILD.wineboot.log" 2>&1 || { cat "$BUILD.wineboot.log"; die "wineboot failed"; }
  wineserver -w
fi

# One wineserver for the whole run instead of one that exits after 3 s idle and is started again:
# fewer chances for a program's start to race the server's (wine_test_launcher.sh covers the rest).
wineserver -p </dev/null >/dev/null 2>&1
say "ctest under $(wine --version) (test lists are read under Wine first)"
(cd "$BUILD" && ctest --output-on-failure -j"$JOBS" "$@") 2>&1 | tee "$LOG"
rc=${PIPESTATUS[0]}
wineserver -k >/dev/null 2>&1 || true

grep -qE '[0-9]+% tests passed, [0-9]+ tests failed out of [0-9]+' "$LOG" \
  || { say "ctest printed no summary"; rc=1; }
# ctest lists skips under "did not run"; only the HID transport may skip (built without hidapi).
unexpected_skips=$(sed -n '/The following tests did not run:/,/^$/p' "$LOG" | grep -E '\(Skipped\)' \
                   | grep -vE ' - TransportHid\.' || true)
if [ -n "$unexpected_skips" ]; then
  say "tests skipped (a skip is not a pass):"; echo "$unexpected_skips"; rc=1
fi
say "took $(( $(date +%s) - started )) s"
exit $rc
