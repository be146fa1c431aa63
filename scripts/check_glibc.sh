#!/usr/bin/env bash
# Checks that shared libraries load on glibc 2.31 (Ubuntu 20.04, the oldest Linux Unity 2022.3
# supports): every symbol version a library asks of glibc (GLIBC_x.y, from `objdump -T` and the
# version references of `objdump -p`) must be 2.31 or older. The engine is C, so a library that
# links libstdc++ fails too, unless --allow-cxx, which instead holds its GLIBCXX / CXXABI
# versions to those of GCC 10's libstdc++ (Ubuntu 20.04, Debian 11).
#
# Usage: scripts/check_glibc.sh [--allow-cxx] [LIB...]
#   LIB defaults to the plugin scripts/build_native_plugin.sh writes:
#   Packages/com.mocap.imu/Runtime/Plugins/Linux/x86_64/libmocap_imu.so
# Output: one PASS or FAIL line per library, a line per offending symbol, then
# "N passed, N failed" (one check per library). Exit status 0 when all pass, 1 otherwise,
# 2 for a command-line mistake.
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MAX_GLIBC=2.31
MAX_GLIBCXX=3.4.28   # GCC 10
MAX_CXXABI=1.3.12    # GCC 10

allow_cxx=0
libs=()
for arg in "$@"; do
  case "$arg" in
    --allow-cxx) allow_cxx=1 ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    -*) echo "check_glibc: unknown option $arg" >&2; exit 2 ;;
    *) libs+=("$arg") ;;
  esac
done
[ ${#libs[@]} -gt 0 ] || libs=("$ROOT/Packages/com.mocap.imu/Runtime/Plugins/Linux/x86_64/libmocap_imu.so")

command -v objdump >/dev/null 2>&1 || { echo "check_glibc: objdump not found (binutils)" >&2; exit 2; }

# Prints "newer" when dotted version $1 is newer than $2, compared number by number
# (2.4 is older than 2.31; 2.2.5 older than 2.3).
version_newer() {
  awk -v a="$1" -v b="$2" 'BEGIN {
    na = split(a, x, "."); nb = split(b, y, "."); n = na > nb ? na : nb
    for (i = 1; i <= n; i++) { if ((x[i] + 0) > (y[i] + 0)) { print "newer"; exit }
                               if ((x[i] + 0) < (y[i] + 0)) exit } }'
}

limit_of() { # family -> newest version allowed
  case "$1" in GLIBC) echo "$MAX_GLIBC" ;; GLIBCXX) echo "$MAX_GLIBCXX" ;; CXXABI) echo "$MAX_CXXABI" ;; esac
}

passed=0
failed=0
for lib in "${libs[@]}"; do
  if [ ! -f "$lib" ]; then
    echo "FAIL $lib: no such file (build it first: scripts/build_native_plugin.sh)"
    failed=$((failed + 1)); continue
  fi
  if ! dynsyms="$(objdump -T "$lib" 2>&1)" || ! headers="$(objdump -p "$lib" 2>&1)"; then
    echo "FAIL $lib: not a shared library objdump can read: $(head -1 <<<"$dynsyms")"
    failed=$((failed + 1)); continue
  fi
  if ! grep -q 'DYNAMIC SYMBOL TABLE' <<<"$dynsyms"; then
    echo "FAIL $lib: no dynamic symbol table (not a shared library?)"
    failed=$((failed + 1)); continue
  fi

  problems=()
  needed="$(awk '$1 == "NEEDED" {print $2}' <<<"$headers")"
  if grep -q '^libstdc++' <<<"$needed" && [ $allow_cxx -eq 0 ]; then
    problems+=("links $(grep '^libstdc++' <<<"$needed" | head -1): the engine is C and must not need the C++ runtime")
  fi

  # Undefined symbols with the version they ask for: "... *UND* ... (GLIBC_2.34) pthread_create".
  wanted="$(awk '$0 ~ /\*UND\*/ {
      for (i = 1; i <= NF; i++) if ($i ~ /^\(?(GLIBC|GLIBCXX|CXXABI)_[0-9.]+\)?$/) {
        v = $i; gsub(/[()]/, "", v); print v, $NF } }' <<<"$dynsyms" | sort -u)"
  # The loader checks the version references themselves; list any no symbol line accounts for.
  refs="$(awk '/^Version References:/ {on = 1; next} on && /^[^ \t]/ {on = 0}
      on && $NF ~ /^(GLIBC|GLIBCXX|CXXABI)_[0-9.]+$/ {print $NF}' <<<"$headers" | sort -u)"
  for ref in $refs; do
    grep -q "^$ref " <<<"$wanted" || wanted+=$'\n'"$ref (a version reference with no symbol listed)"
  done

  newest=""
  n_symbols=0
  while read -r version symbol; do
    [ -n "$version" ] || continue
    n_symbols=$((n_symbols + 1))
    family="${version%%_*}"
    number="${version#*_}"
    if [ "$family" = GLIBC ] && { [ -z "$newest" ] || [ -n "$(version_newer "$number" "$newest")" ]; }; then
      newest="$number"
    fi
    if [ "$family" != GLIBC ] && [ $allow_cxx -eq 0 ]; then
      continue # already refused as a whole: libstdc++ is linked
    fi
    limit="$(limit_of "$family")"
    if [ -n "$(version_newer "$number" "$limit")" ]; then
      problems+=("$symbol needs $version (newer than ${family}_$limit)")
    fi
  done <<<"$wanted"

  if [ ${#problems[@]} -eq 0 ]; then
    echo "PASS $lib: newest GLIBC_${newest:-none} of $n_symbols versioned symbols (limit GLIBC_$MAX_GLIBC)"
    passed=$((passed + 1))
  else
    echo "FAIL $lib: ${#problems[@]} requirement(s) that glibc $MAX_GLIBC (Ubuntu 20.04) cannot meet:"
    for p in "${problems[@]}"; do echo "  $p"; done
    failed=$((failed + 1))
  fi
done

echo "$passed passed, $failed failed"
[ $failed -eq 0 ]
