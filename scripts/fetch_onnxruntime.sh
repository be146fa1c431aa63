#!/usr/bin/env bash
# Fetches the ONNX Runtime C library and headers the engine loads at run time (dlopen) and
# compiles against (headers only). Source: the npm package com.github.asus4.onnxruntime@0.4.9
# (a Unity package of ONNX Runtime 1.29.0, MIT licence). Only these are kept:
#   build/third_party/onnxruntime/lib/libonnxruntime.so (+ libonnxruntime.so.1 SONAME link)
#   build/third_party/onnxruntime/include/*.h           (the C API headers)
#   build/third_party/onnxruntime/win-x64/onnxruntime.dll, onnxruntime_providers_shared.dll
#                                                       (the Windows build, for the engine's
#                                                       tests under Wine: scripts/test_windows.sh)
# build/ is git-ignored: the binaries are never committed.
#
# Idempotent: a second run checks what is there and does nothing. The tarball is verified
# against npm's published integrity (sha512) and shasum (sha1) before anything is extracted.
# Usage: scripts/fetch_onnxruntime.sh [--force]
set -euo pipefail

PKG=com.github.asus4.onnxruntime
VERSION=0.4.9
TARBALL=$PKG-$VERSION.tgz
SHA1=3659f34012db8208ffb7f67d704204cb08792fed
SHA512_B64='BkzxduSZ9IkeDP6Q8lz2TFU2ie7hSSvS7ZIfzMooExoq0CNzJnuuGaUJ7IsojBgqO4ouD1jXah8OYyJbCN29Fg=='
REGISTRY_URL=https://registry.npmjs.org/$PKG/-/$TARBALL

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
THIRD="$ROOT/build/third_party"
DEST="$THIRD/onnxruntime"
STAMP="$DEST/.fetched-$PKG-$VERSION"

say() { echo "fetch_onnxruntime: $*"; }
die() { echo "fetch_onnxruntime: error: $*" >&2; exit 1; }

force=0
[ "${1:-}" = "--force" ] && force=1

WIN_DLLS=(onnxruntime.dll onnxruntime_providers_shared.dll)
have_windows() {
  local f
  for f in "${WIN_DLLS[@]}"; do [ -f "$DEST/win-x64/$f" ] || return 1; done
}
have_linux() {
  [ -f "$STAMP" ] && [ -f "$DEST/lib/libonnxruntime.so" ] && [ -L "$DEST/lib/libonnxruntime.so.1" ] \
    && [ -f "$DEST/include/onnxruntime_c_api.h" ]
}

if [ $force -eq 0 ] && have_linux && have_windows; then
  say "ONNX Runtime from $PKG@$VERSION already in $DEST (nothing to do)"
  exit 0
fi

mkdir -p "$THIRD"

verify() { # file -> 0 when both checksums match
  local f="$1" sha1 sha512
  sha1=$(sha1sum "$f" | cut -d' ' -f1)
  sha512=$(openssl dgst -sha512 -binary "$f" 2>/dev/null | base64 -w0 || true)
  if [ -z "$sha512" ]; then # no openssl: derive base64 from sha512sum's hex
    sha512=$(sha512sum "$f" | cut -d' ' -f1 | xxd -r -p 2>/dev/null | base64 -w0 || true)
  fi
  [ "$sha1" = "$SHA1" ] || { echo "  sha1 $sha1 != $SHA1" >&2; return 1; }
  if [ -n "$sha512" ]; then
    [ "$sha512" = "$SHA512_B64" ] || { echo "  sha512 $sha512 != expected" >&2; return 1; }
  fi
  return 0
}

if [ -f "$THIRD/$TARBALL" ] && verify "$THIRD/$TARBALL"; then
  say "reusing verified $THIRD/$TARBALL"
else
  rm -f "$THIRD/$TARBALL"
  if command -v npm >/dev/null 2>&1; then
    say "npm pack $PKG@$VERSION -> $THIRD"
    (cd "$THIRD" && npm pack --silent "$PKG@$VERSION" >/dev/null)
  elif command -v curl >/dev/null 2>&1; then
    say "npm not found; downloading $REGISTRY_URL with curl"
    curl -fsSL -o "$THIRD/$TARBALL" "$REGISTRY_URL"
  elif command -v wget >/dev/null 2>&1; then
    say "npm not found; downloading $REGISTRY_URL with wget"
    wget -q -O "$THIRD/$TARBALL" "$REGISTRY_URL"
  else
    die "need npm, curl or wget to download $PKG@$VERSION (scripts/setup.sh installs npm)"
  fi
  [ -f "$THIRD/$TARBALL" ] || die "the download did not produce $THIRD/$TARBALL"
  if ! verify "$THIRD/$TARBALL"; then
    mv "$THIRD/$TARBALL" "$THIRD/$TARBALL.rejected"
    die "checksum mismatch for $TARBALL (kept as $TARBALL.rejected); refusing to extract"
  fi
  say "checksums verified (sha1 $SHA1, sha512 integrity)"
fi

work=$(mktemp -d "$THIRD/extract.XXXXXX")
trap 'rm -rf "$work"' EXIT

# The Windows x64 DLLs, from the same verified tarball, beside the Linux files (which stay as
# they are when already there: other builds may be using them).
if [ $force -eq 1 ] || ! have_windows; then
  win_members=()
  for f in "${WIN_DLLS[@]}"; do
    m=$(tar -tzf "$THIRD/$TARBALL" | grep -E "^package/Plugins/Windows/x64/${f//./\\.}\$" | head -n1 || true)
    [ -n "$m" ] || die "$TARBALL has no Plugins/Windows/x64/$f"
    win_members+=("$m")
  done
  tar -xzf "$THIRD/$TARBALL" -C "$work" "${win_members[@]}"
  mkdir -p "$DEST/win-x64"
  for m in "${win_members[@]}"; do cp "$work/$m" "$DEST/win-x64/$(basename "$m")"; done
  say "extracted ${WIN_DLLS[*]} -> $DEST/win-x64"
fi
if [ $force -eq 0 ] && have_linux; then
  exit 0
fi

# Extract only the Linux x64 library and the C headers (from the iOS framework's Headers folder).
lib_member=$(tar -tzf "$THIRD/$TARBALL" | grep -E '^package/Plugins/Linux/x64/libonnxruntime\.so$' | head -n1 || true)
[ -n "$lib_member" ] || die "$TARBALL has no Plugins/Linux/x64/libonnxruntime.so"
hdr_member=$(tar -tzf "$THIRD/$TARBALL" | grep -E '/Headers/onnxruntime_c_api\.h$' | head -n1 || true)
[ -n "$hdr_member" ] || die "$TARBALL has no onnxruntime_c_api.h"
hdr_dir=$(dirname "$hdr_member")
tar -xzf "$THIRD/$TARBALL" -C "$work" "$lib_member" "$hdr_dir"

rm -rf "$DEST/lib" "$DEST/include" "$STAMP"
mkdir -p "$DEST/lib" "$DEST/include"
cp "$work/$lib_member" "$DEST/lib/libonnxruntime.so"
# The C API header and the headers it includes (transitively) from the same folder.
todo=(onnxruntime_c_api.h)
copied=()
while [ ${#todo[@]} -gt 0 ]; do
  h=${todo[0]}
  todo=("${todo[@]:1}")
  [[ " ${copied[*]:-} " == *" $h "* ]] && continue
  [ -f "$work/$hdr_dir/$h" ] || continue # a system header
  cp "$work/$hdr_dir/$h" "$DEST/include/$h"
  copied+=("$h")
  while read -r inc; do todo+=("$inc"); done < <(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$work/$hdr_dir/$h")
done
soname=$(objdump -p "$DEST/lib/libonnxruntime.so" 2>/dev/null | awk '/SONAME/ {print $2}' || true)
[ -n "$soname" ] || soname=libonnxruntime.so.1
ln -sfn libonnxruntime.so "$DEST/lib/$soname"
[ "$soname" = libonnxruntime.so.1 ] || ln -sfn libonnxruntime.so "$DEST/lib/libonnxruntime.so.1"
api=$(sed -n 's/^#define ORT_API_VERSION \([0-9]*\).*/\1/p' "$DEST/include/onnxruntime_c_api.h")
touch "$STAMP"
say "extracted $lib_member -> $DEST/lib/libonnxruntime.so ($(du -h "$DEST/lib/libonnxruntime.so" | cut -f1), SONAME $soname, link ${soname} -> libonnxruntime.so)"
say "headers ${copied[*]} -> $DEST/include (ORT_API_VERSION ${api:-?})"
