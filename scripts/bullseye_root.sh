#!/usr/bin/env bash
# A Debian 11 "bullseye" root (glibc 2.31, the glibc of Ubuntu 20.04, the oldest Linux that Unity
# 2022.3 supports) for building the Linux plugin against glibc 2.31 and loading it there. It is
# made once with debootstrap and kept outside the repository; a root left half-made by an
# interrupted run, or made with another package list, is made again.
#
# Usage: scripts/bullseye_root.sh path              make the root when missing; print its path
#        scripts/bullseye_root.sh run CMD [ARG...]   run CMD inside it (chroot, clean environment)
# Environment:
#   MOCAP_BULLSEYE_ROOT  where the root lives (default /var/cache/mocap-imu/bullseye-amd64);
#                        delete the folder to refresh it
#   MOCAP_DEBIAN_MIRROR  the Debian archive to fetch bullseye from (default: the archive this
#                        machine's apt uses for its own release)
# Needs root (debootstrap and chroot) and the debootstrap package.
set -euo pipefail

ROOTFS="${MOCAP_BULLSEYE_ROOT:-/var/cache/mocap-imu/bullseye-amd64}"
SUITE=bullseye
# build-essential for C and the C++ compiler CMake's project() asks for, hidapi for
# build_native_plugin.sh --with-hid; nothing else is needed to build the engine or to compile
# and run the smoke loader.
PACKAGES="build-essential,cmake,pkg-config,libhidapi-dev"
MARKER="etc/mocap-imu-root"   # written last: its presence means debootstrap finished

say() { echo "bullseye_root: $*" >&2; }
die() { echo "bullseye_root: error: $*" >&2; exit 1; }

usage() { sed -n '7,14p' "$0" >&2; exit 2; }

# The Debian archive this machine's apt uses for its own release (the suite named exactly by
# VERSION_CODENAME, not -security or -updates), in either sources format.
host_mirror() {
  local codename
  codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
  [ -n "$codename" ] || return 1
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk -v want="$codename" '
      function flush() { if (ok && uri != "") { print uri; found = 1; exit } ok = 0; uri = "" }
      /^[ \t]*$/ { flush(); next }
      /^URIs:/ { uri = $2 }
      /^Suites:/ { for (i = 2; i <= NF; i++) if ($i == want) ok = 1 }
      END { if (!found) flush() }' "$f"
  done
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    # deb [options] URI SUITE COMPONENTS...
    sed -E 's/\[[^]]*\]//' "$f" | awk -v want="$codename" '$1 == "deb" && $3 == want { print $2 }'
  done
}

root_is_complete() {
  [ -f "$ROOTFS/$MARKER" ] && [ "$(cat "$ROOTFS/$MARKER")" = "$SUITE $PACKAGES" ] \
    && [ -x "$ROOTFS/usr/bin/cmake" ] && [ -x "$ROOTFS/usr/bin/gcc" ]
}

make_root() {
  [ "$(id -u)" -eq 0 ] || die "making the bullseye root needs root (debootstrap)"
  command -v debootstrap >/dev/null 2>&1 || die "debootstrap not found (scripts/setup.sh installs it)"
  local mirror="${MOCAP_DEBIAN_MIRROR:-}"
  if [ -z "$mirror" ]; then
    mirror="$(host_mirror | head -1 || true)"
    [ -n "$mirror" ] || die "no Debian archive found in /etc/apt/sources.list*; set MOCAP_DEBIAN_MIRROR"
  fi
  local staging="$ROOTFS.partial"
  rm -rf "$staging"
  [ ! -e "$ROOTFS" ] || { say "$ROOTFS is incomplete or outdated: making it again"; rm -rf "$ROOTFS"; }
  mkdir -p "$(dirname "$ROOTFS")"
  say "debootstrap $SUITE ($PACKAGES) from $mirror into $ROOTFS (once; a few minutes)"
  local log="$staging.log"
  if ! debootstrap --variant=minbase --arch=amd64 --include="$PACKAGES" "$SUITE" "$staging" \
       "$mirror" >"$log" 2>&1; then
    tail -30 "$log" >&2
    [ ! -f "$staging/debootstrap/debootstrap.log" ] || tail -30 "$staging/debootstrap/debootstrap.log" >&2
    die "debootstrap failed (log: $log); if the archive no longer carries $SUITE, point MOCAP_DEBIAN_MIRROR at one that does"
  fi
  # Downloaded packages and indexes are only needed to install: the cache keeps what builds need.
  rm -rf "$staging"/var/cache/apt/archives/*.deb "$staging"/var/lib/apt/lists/*_Packages
  echo "$SUITE $PACKAGES" >"$staging/$MARKER"
  mv "$staging" "$ROOTFS"
  rm -f "$log"
}

ensure_root() {
  root_is_complete && return 0
  mkdir -p "$(dirname "$ROOTFS")"
  # Two runs at once (a developer and CI) make the root once.
  exec 9>"$ROOTFS.lock"
  flock 9
  root_is_complete || make_root
  flock -u 9
}

[ $# -ge 1 ] || usage
case "$1" in
  path)
    [ $# -eq 1 ] || usage
    ensure_root
    echo "$ROOTFS"
    ;;
  run)
    shift
    [ $# -ge 1 ] || usage
    [ "$(id -u)" -eq 0 ] || die "entering the bullseye root needs root (chroot)"
    ensure_root
    clean_env=(env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root
               LC_ALL=C.UTF-8)
    # /proc inside the root (ONNX Runtime reads /proc/cpuinfo) is mounted in a mount namespace of
    # its own: it goes away with the command, so nothing stays mounted in the cached root (and
    # deleting the root cannot reach through a mount). Where namespaces are not allowed the
    # command runs without /proc.
    if unshare --mount --pid --fork --mount-proc="$ROOTFS/proc" true 2>/dev/null; then
      exec "${clean_env[@]}" unshare --mount --pid --fork --mount-proc="$ROOTFS/proc" \
        chroot "$ROOTFS" "$@"
    fi
    exec "${clean_env[@]}" chroot "$ROOTFS" "$@"
    ;;
  -h|--help) sed -n '7,14p' "$0"; exit 0 ;;
  *) usage ;;
esac
