#!/usr/bin/env bash
# Builds the engine (Release) as the package's Windows x86_64 plugin with MinGW-w64:
#   Packages/com.mocap.imu/Runtime/Plugins/Windows/x86_64/mocap_imu.dll  (+ generated .meta files)
# (scripts/build_native_plugin.sh --windows runs this). A build output, ignored by git like the
# Linux plugin. The DLL needs only Windows' own DLLs (GCC's runtimes are linked in statically)
# and exports only the MOCAP_API functions; ONNX Runtime is loaded at run time from the path the
# Unity glue gives. Checked here by loading the stripped DLL under Wine and opening the shipped
# model with the Windows ONNX Runtime of the same npm package (scripts/fetch_onnxruntime.sh).
# Usage: scripts/build_windows_plugin.sh
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PKG="$ROOT/Packages/com.mocap.imu"
NATIVE="$PKG/Native~"
BUILD="$ROOT/build/windows-plugin"
DEST="$PKG/Runtime/Plugins/Windows/x86_64"
JOBS="$(nproc 2>/dev/null || echo 2)"
MINGW=x86_64-w64-mingw32

say() { echo "build_windows_plugin: $*"; }
die() { echo "build_windows_plugin: error: $*" >&2; exit 1; }

for tool in $MINGW-gcc-posix $MINGW-objdump $MINGW-strip wine cmake; do
  command -v "$tool" >/dev/null 2>&1 || die "$tool not found: run scripts/setup.sh"
done
"$ROOT/scripts/fetch_onnxruntime.sh" >/dev/null

mkdir -p "$BUILD"
say "configure + build (Release, MinGW-w64) in $BUILD"
cmake -S "$NATIVE" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DMOCAP_BUILD_TESTS=OFF \
  -DCMAKE_TOOLCHAIN_FILE="$NATIVE/cmake/mingw-w64-x86_64.cmake" >"$BUILD.configure.log" 2>&1 \
  || { cat "$BUILD.configure.log"; die "cmake configure failed"; }
cmake --build "$BUILD" --target mocap_imu -j"$JOBS" >"$BUILD.build.log" 2>&1 \
  || { tail -50 "$BUILD.build.log"; die "build failed"; }
dll="$BUILD/mocap_imu.dll"
[ -f "$dll" ] || die "the build produced no $dll"

imports="$($MINGW-objdump -p "$dll" | awk '/DLL Name:/ {print $3}' | tr '\n' ' ')"
for d in $imports; do
  case "${d,,}" in kernel32.dll|msvcrt.dll|ws2_32.dll) ;;
    *) die "mocap_imu.dll needs $d (only Windows' own DLLs are allowed)";; esac
done
# The export table: "[ordinal] name" lines after "[Ordinal/Name Pointer] Table".
exports="$($MINGW-objdump -p "$dll" | sed -n '/\[Ordinal\/Name Pointer\] Table/,/^$/p' \
           | awk '/^[ \t]*\[/ && NF >= 2 {print $NF}' | grep -v 'Table$' || true)"
n_exports="$(grep -c '^mocap_' <<<"$exports" || true)"
others="$(grep -v '^mocap_' <<<"$exports" || true)"
[ "$n_exports" -gt 0 ] || die "mocap_imu.dll exports no mocap_ function"
[ -z "$others" ] || die "mocap_imu.dll exports non-API symbols: $others"

mkdir -p "$DEST"
$MINGW-strip --strip-unneeded -o "$DEST/mocap_imu.dll" "$dll"
say "$DEST/mocap_imu.dll: $(stat -c %s "$DEST/mocap_imu.dll") bytes, $n_exports exported mocap_ functions, imports ${imports% }"

# Smoke test under Wine, in a prefix of its own.
smoke="$BUILD/smoke"
mkdir -p "$smoke"
$MINGW-gcc-posix -std=c11 -O1 -Wall -Wextra -Werror -static -I"$NATIVE/include" \
  -o "$smoke/windows_plugin_smoke.exe" "$ROOT/scripts/windows_plugin_smoke.c" \
  || die "the smoke loader does not compile"
export WINEPREFIX="$BUILD/wine-prefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="
[ -f "$WINEPREFIX/system.reg" ] || { wineboot -i >"$BUILD.wineboot.log" 2>&1 && wineserver -w; } \
  || die "wineboot failed (log: $BUILD.wineboot.log)"
wine "$smoke/windows_plugin_smoke.exe" "$DEST/mocap_imu.dll" "$PKG/Runtime/Models/mocap_pose_int8.onnx" \
  "$ROOT/build/third_party/onnxruntime/win-x64/onnxruntime.dll" | tr -d '\r' | sed 's/^/build_windows_plugin: smoke test under Wine: /' \
  || die "the built plugin does not load or open the shipped model under Wine"
wineserver -k >/dev/null 2>&1 || true

/usr/bin/python3 "$ROOT/scripts/unity_meta.py" --quiet
/usr/bin/python3 "$ROOT/scripts/package_lint.py" >/dev/null \
  || { /usr/bin/python3 "$ROOT/scripts/package_lint.py"; die "the package does not lint"; }
say "package .meta files regenerated; package_lint passes"
