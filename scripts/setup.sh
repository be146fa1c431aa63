#!/usr/bin/env bash
# Installs everything the project needs on a fresh Debian 12 machine (run as root or with sudo).
# Fast no-op when everything is already there.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

PACKAGES=(
  build-essential cmake pkg-config
  googletest libgtest-dev            # C test framework
  libhidapi-dev                      # HID-class receivers
  clang-14 libclang-rt-14-dev        # libFuzzer + ThreadSanitizer runtime
  python3 python3-numpy python3-pytest
  python3-torch python3-onnx python3-tqdm python3-matplotlib python3-scipy   # training/
  libopenblas0-pthread               # torch on the CPU is ~10x slower with the reference BLAS
  liblo-tools                        # oscdump: a real OSC receiver for interop tests
  gcc-mingw-w64-x86-64-win32         # checks that the engine compiles for Windows
  gcc-mingw-w64-x86-64-posix g++-mingw-w64-x86-64-posix   # the Windows build (GoogleTest needs std::mutex)
  wine wine64                        # runs the Windows build's tests (scripts/test_windows.sh)
  debootstrap binutils               # the Linux plugin built and smoke-loaded on glibc 2.31, objdump
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm fetches ONNX Runtime; a machine may already have it from another Node.js distribution,
# whose nodejs package Debian's npm would conflict with.
command -v npm >/dev/null 2>&1 || missing+=(npm)

if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# ONNX Runtime (pinned, checksum-verified, never committed) for the engine and training/.
if [ -x "$ROOT/scripts/fetch_onnxruntime.sh" ]; then
  "$ROOT/scripts/fetch_onnxruntime.sh"
fi
