#!/usr/bin/env bash
# Installs everything the project needs on a fresh Debian 12 machine (run as root or with sudo).
# Fast no-op when everything is already there.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  googletest libgtest-dev            # C test framework
  libhidapi-dev                      # HID-class receivers
  clang-14 libclang-rt-14-dev        # libFuzzer + ThreadSanitizer runtime
  python3 python3-numpy python3-pytest
  liblo-tools                        # oscdump: a real OSC receiver for interop tests
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
