#!/usr/bin/env bash
# ctest's launcher for the Windows test programs (test_windows.sh hands it to CMake as the
# cross-compiling emulator): runs one program under Wine, passing its output and exit status on.
#
# Wine now and then fails to start a process at all (seen once in CI: a deterministic OSC
# encoding test "failed" in 0.00 s with no output). A GoogleTest program prints its banner before
# any test runs, so a run that exits non-zero having printed nothing never reached our code: that
# run, and only that one, is started again (at most three starts in all), saying so on stderr. A
# program that prints anything and then fails is a failure, whatever Wine did, with one exception:
# Wine's own Linux-side loader can abort while the process is being torn down (seen once in CI:
# "Inconsistency detected by ld.so: dl-fini.c ..." after GoogleTest had printed PASSED). That
# status is the host loader's, not the program's, so that run is started again too and has to
# pass whole on its own.
#
# Output and errors go through files, never straight to ctest's pipes: Wine's own background
# processes (wineserver, winedevice.exe) inherit what the program was given and would hold those
# pipes open, so ctest would wait for them long after the program ended.
set -uo pipefail
wine="${MOCAP_WINE_BINARY:-wine}"
out=$(mktemp) || exit 1
err=$(mktemp) || exit 1
child=
# ctest stops a program that runs past its timeout: show what it printed, and stop it too.
trap '[ -n "$child" ] && kill "$child" 2>/dev/null; cat "$out"; cat "$err" >&2; rm -f "$out" "$err"
      exit 143' TERM INT
for attempt in 1 2 3; do
  "$wine" "$@" >"$out" 2>"$err" </dev/null &
  child=$!
  wait "$child"
  rc=$?
  child=
  cat "$out"; cat "$err" >&2
  [ "$rc" -eq 0 ] && break
  if grep -q "Inconsistency detected by ld.so" "$err" "$out"; then
    echo "wine_test_launcher: $(basename "$1") exited $rc after Wine's host loader aborted at" \
         "process teardown (start $attempt of 3)" >&2
  elif [ -s "$out" ]; then
    break
  else
    echo "wine_test_launcher: $(basename "$1") exited $rc under Wine before printing anything" \
         "(start $attempt of 3)" >&2
  fi
done
rm -f "$out" "$err"
exit "$rc"
