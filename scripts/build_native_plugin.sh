#!/usr/bin/env bash
# Builds the native engine (Release) as the package's Linux x86_64 plugin:
#   Packages/com.mocap.imu/Runtime/Plugins/Linux/x86_64/libmocap_imu.so  (+ generated .meta files)
# The plugin is a build output: Runtime/Plugins/ is ignored by git (binaries belong to the build,
# not to git; the importer settings live in scripts/unity_meta.py, which regenerates the .meta
# files with their path-derived GUIDs). Windows and macOS steps: Documentation~/index.md.
#
# The plugin is compiled and linked inside a Debian 11 root (glibc 2.31, the glibc of Ubuntu
# 20.04, the oldest Linux Unity 2022.3 supports; scripts/bullseye_root.sh makes it once, outside
# the repository), so it asks nothing newer of glibc than 2.31: scripts/check_glibc.sh verifies
# that, and the built plugin replays a capture through the pose model inside that root (glibc
# 2.31) and here. Needs root or sudo (debootstrap, chroot).
#
# Usage: scripts/build_native_plugin.sh [--with-hid] [--pack] [--host-toolchain]
#   --with-hid  link hidapi for the HID transport (the plugin then needs libhidapi-hidraw0 on the
#               user's machine); by default the plugin depends on nothing but glibc
#   --pack      also write out/com.mocap.imu-<version>.tgz, a tarball Unity's Package Manager
#               installs with "Add package from tarball" (the package with its plugin)
#   --host-toolchain  compile with this machine's compiler instead of in the glibc 2.31 root (no
#               root needed); the glibc check then passes only on a machine with glibc <= 2.31
#   --windows   build the Windows x86_64 plugin instead (Runtime/Plugins/Windows/x86_64/
#               mocap_imu.dll, MinGW-w64, smoke-tested under Wine): scripts/build_windows_plugin.sh
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PKG="$ROOT/Packages/com.mocap.imu"
BUILD="$ROOT/build/glibc231-plugin"
DEST="$PKG/Runtime/Plugins/Linux/x86_64"
JOBS="$(nproc 2>/dev/null || echo 2)"

with_hid=OFF
pack=0
host_toolchain=0
for arg in "$@"; do
  case "$arg" in
    --windows) exec "$ROOT/scripts/build_windows_plugin.sh" ;;
    --with-hid) with_hid=ON ;;
    --pack) pack=1 ;;
    --host-toolchain) host_toolchain=1 ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "build_native_plugin: unknown option $arg" >&2; exit 2 ;;
  esac
done

say() { echo "build_native_plugin: $*"; }
die() { echo "build_native_plugin: error: $*" >&2; exit 1; }

[ "$(uname -s)" = Linux ] || die "this script builds the Linux plugin; see Documentation~/index.md for Windows and macOS"
[ "$(uname -m)" = x86_64 ] || die "the Linux plugin is x86_64 (this machine is $(uname -m))"

# ONNX Runtime headers (the library itself is loaded at run time, never linked).
"$ROOT/scripts/fetch_onnxruntime.sh" >/dev/null

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
bullseye() { as_root "$ROOT/scripts/bullseye_root.sh" "$@"; }
# The copy of the sources inside the root mirrors the repository's layout, so CMake finds the
# ONNX Runtime headers where it looks for them (build/third_party/onnxruntime). One folder per
# run: two builds at once (CI and a developer) share the cached root.
IN_ROOT="/work/mocap_imu.$$"

if [ $host_toolchain -eq 1 ]; then
  BUILD="$ROOT/build/glibc-host-plugin"
  say "configure + build (Release, HID $with_hid, this machine's toolchain) in $BUILD"
  cmake -S "$PKG/Native~" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DMOCAP_BUILD_TESTS=OFF \
    -DMOCAP_WITH_HIDAPI="$with_hid" >"$BUILD.configure.log" 2>&1 \
    || { cat "$BUILD.configure.log"; die "cmake configure failed"; }
  cmake --build "$BUILD" --target mocap_imu -j"$JOBS" >"$BUILD.build.log" 2>&1 \
    || { tail -50 "$BUILD.build.log"; die "build failed"; }
else
  rootfs="$(bullseye path)" || die "no Debian 11 root to build in (scripts/bullseye_root.sh)"
  say "configure + build (Release, HID $with_hid) in the glibc 2.31 root $rootfs"
  work="$rootfs$IN_ROOT"
  trap 'as_root rm -rf "$work"' EXIT
  as_root mkdir -p "$work/src/Packages/com.mocap.imu" "$work/src/build/third_party/onnxruntime"
  tar -C "$PKG" --exclude='Native~/build*' -cf - 'Native~' \
    | as_root tar -C "$work/src/Packages/com.mocap.imu" -xf -
  as_root cp -r "$ROOT/build/third_party/onnxruntime/include" "$work/src/build/third_party/onnxruntime/"
  mkdir -p "$BUILD"
  bullseye run cmake -S "$IN_ROOT/src/Packages/com.mocap.imu/Native~" -B "$IN_ROOT/build" \
    -DCMAKE_BUILD_TYPE=Release -DMOCAP_BUILD_TESTS=OFF -DMOCAP_WITH_HIDAPI="$with_hid" \
    >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; die "cmake configure failed"; }
  bullseye run cmake --build "$IN_ROOT/build" --target mocap_imu -j"$JOBS" >"$BUILD.build.log" 2>&1 \
    || { tail -50 "$BUILD.build.log"; die "build failed"; }
  cp "$work/build/libmocap_imu.so" "$BUILD/libmocap_imu.so"
fi

lib="$BUILD/libmocap_imu.so"
[ -f "$lib" ] || die "the build produced no $lib"

# The plugin must not link ONNX Runtime (it dlopens the path the Unity glue passes) and, without
# --with-hid, must need nothing beyond glibc.
needed="$(objdump -p "$lib" | awk '/NEEDED/ {print $2}' | tr '\n' ' ')"
case "$needed" in *onnxruntime*) die "libmocap_imu.so links ONNX Runtime ($needed)";; esac
if [ "$with_hid" = OFF ]; then
  for n in $needed; do
    case "$n" in libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*|ld-linux*) ;;
      *) die "unexpected dependency $n of libmocap_imu.so";; esac
  done
fi
exports="$(nm -D --defined-only "$lib" | awk '$2 == "T" {print $3}')"
n_exports="$(grep -c '^mocap_' <<<"$exports" || true)"
others="$(grep -v '^mocap_' <<<"$exports" || true)"
[ "$n_exports" -gt 0 ] || die "libmocap_imu.so exports no mocap_ function"
[ -z "$others" ] || die "libmocap_imu.so exports non-API symbols: $others"
glibc="$(objdump -T "$lib" | grep -Eo 'GLIBC_[0-9.]+' | sort -t. -k2,2n -k3,3n -u | tail -1)"

mkdir -p "$DEST"
cp "$lib" "$DEST/libmocap_imu.so"
strip --strip-unneeded "$DEST/libmocap_imu.so"
say "$DEST/libmocap_imu.so: $(stat -c %s "$DEST/libmocap_imu.so") bytes, $n_exports exported mocap_ functions, needs ${needed% } (newest symbol $glibc)"

"$ROOT/scripts/check_glibc.sh" "$DEST/libmocap_imu.so" | sed 's/^/build_native_plugin: /' \
  || { rm -f "$DEST/libmocap_imu.so"
       die "the plugin needs a glibc newer than 2.31 (Ubuntu 20.04), removed; build it without --host-toolchain"; }

# The plugin must load and work on glibc 2.31 itself: dlopen it inside the root and replay the
# package's test capture through the shipped model with the registry package's ONNX Runtime.
if [ $host_toolchain -eq 0 ]; then
  smoke="$work/smoke"
  as_root mkdir -p "$smoke"
  as_root cp "$DEST/libmocap_imu.so" "$PKG/Runtime/Models/mocap_pose_int8.onnx" \
    "$ROOT/build/third_party/onnxruntime/lib/libonnxruntime.so" \
    "$PKG/Tests/Runtime/Fixtures/walk.cap" "$ROOT/scripts/plugin_smoke_load.c" "$smoke/"
  bullseye run gcc -std=gnu11 -O1 -Wall -Wextra -Werror \
    -I"$IN_ROOT/src/Packages/com.mocap.imu/Native~/include" -o "$IN_ROOT/smoke/plugin_smoke_load" \
    "$IN_ROOT/smoke/plugin_smoke_load.c" -ldl -lm || die "the smoke loader does not compile"
  bullseye run "$IN_ROOT/smoke/plugin_smoke_load" "$IN_ROOT/smoke/libmocap_imu.so" \
    "$IN_ROOT/smoke/mocap_pose_int8.onnx" "$IN_ROOT/smoke/libonnxruntime.so" "$IN_ROOT/smoke/walk.cap" \
    | sed 's/^/build_native_plugin: in the glibc 2.31 root: /' \
    || die "the plugin does not load or run on glibc 2.31"
fi

# Smoke test of the stripped plugin as Unity would use it: load it, open the shipped model with
# ONNX Runtime given by explicit path (the same libonnxruntime.so the registry package ships).
ort_lib="$ROOT/build/third_party/onnxruntime/lib/libonnxruntime.so"
/usr/bin/python3 - "$DEST/libmocap_imu.so" "$PKG/Runtime/Models/mocap_pose_int8.onnx" "$ort_lib" <<'PY' \
  || die "the built plugin could not open the shipped model"
import ctypes, sys
lib = ctypes.CDLL(sys.argv[1])
lib.mocap_version_string.restype = ctypes.c_char_p
lib.mocap_last_error.restype = ctypes.c_char_p
class Options(ctypes.Structure):  # mocap_model_options (include/mocap_imu.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("execution_provider", ctypes.c_int32),
                ("intra_op_threads", ctypes.c_int32), ("optimization_level", ctypes.c_int32),
                ("cuda_device", ctypes.c_int32), ("onnxruntime_path", ctypes.c_char * 260)]
opts = Options()
lib.mocap_model_options_defaults(ctypes.byref(opts))
opts.onnxruntime_path = sys.argv[3].encode()
model = ctypes.c_void_p()
status = lib.mocap_model_open(sys.argv[2].encode(), ctypes.byref(opts), ctypes.byref(model))
if status != 0:
    print("mocap_model_open:", lib.mocap_last_error().decode(), file=sys.stderr)
    sys.exit(1)
lib.mocap_model_close(model)
print(f"build_native_plugin: smoke test: engine {lib.mocap_version_string().decode()} opened "
      f"the shipped model with ONNX Runtime from {sys.argv[3]}")
PY

/usr/bin/python3 "$ROOT/scripts/unity_meta.py" --quiet
/usr/bin/python3 "$ROOT/scripts/package_lint.py" >/dev/null \
  || { /usr/bin/python3 "$ROOT/scripts/package_lint.py"; die "the package does not lint"; }
say "package .meta files regenerated; package_lint passes"

if [ $pack -eq 1 ]; then
  version="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["version"])' "$PKG/package.json")"
  mkdir -p "$ROOT/out"
  tgz="$ROOT/out/com.mocap.imu-$version.tgz"
  # Unity expects the package under "package/"; engine build folders and dot-files stay out.
  tar -C "$ROOT/Packages" --exclude='Native~/build*' --exclude='.*' --sort=name \
      --owner=0 --group=0 --numeric-owner --mtime='2000-01-01 00:00Z' \
      --transform 's,^com\.mocap\.imu,package,' -czf "$tgz" com.mocap.imu
  say "packed $tgz ($(stat -c %s "$tgz") bytes)"
fi
