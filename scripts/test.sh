#!/usr/bin/env bash
# Runs every test suite of the project and ends with one line "N passed, N failed, N skipped".
#   engine:       ctest on a normal build, an ASan+UBSan build and (threading suites) a TSan build
#   fuzz:         the HiPNUC decoder and the capture / calibration file readers under
#                 libFuzzer for a bounded time
#   windows:      the engine, mocapctl and the engine's tests built with MinGW-w64, the tests
#                 run under Wine with the Windows ONNX Runtime DLL (scripts/test_windows.sh);
#                 the shipped Release DLL built and loaded under Wine (build_windows_plugin.sh)
#   linux plugin: the plugin built in a glibc 2.31 root (scripts/build_native_plugin.sh), replayed
#                 there and here, and no symbol newer than GLIBC_2.31 (scripts/check_glibc.sh)
#   dotnet:       the C# core's NUnit tests against the real native library, and the Unity
#                 compile gate: every asmdef and sample of the package compiled against a
#                 declaration-only Unity API (2022.3 and Unity 6, editor and players), which also
#                 fails a component or settings field shown in the inspector without a tooltip
#   python:       pytest over training/
#   unity package: pytest over scripts/tests (.meta generator and package linter, incl. a lint
#                 of the real package: run scripts/unity_meta.py after adding files)
#   pose accuracy: the main job's replay of a generated capture through the shipped model stays
#                 within bounds of today's accuracy (scripts/tests/test_pose_accuracy.py)
# The counts are honest (scripts/test_results.py reads every runner's results):
#   - a skipped test is counted as skipped, never as passed, and a skip that no line of
#     scripts/allowed_skips.txt accepts is a failure (it nearly always means a missing dependency);
#   - a suite that executed no test, or a check that ran on zero files, is a failure;
#   - compile checks count compile units, not tests: only a unit that fails adds to the total.
# Environment: MOCAP_FUZZ_SECONDS (default 60), MOCAP_SKIP_SANITIZERS=1 for a quick local run
# (the sanitizer and fuzz suites are then listed as skipped), MOCAP_TEST_BUILD_DIR (default build/)
# for the suites' build folders and logs.
#
# A new suite is one block: run it with its output in a log, then one of
#   record_from "name" ctest|pytest|dotnet|counts|units LOG_OR_RESULTS_FILE
# (see scripts/test_results.py for what each kind reads).
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
NATIVE="$ROOT/Packages/com.mocap.imu/Native~"
BUILD="${MOCAP_TEST_BUILD_DIR:-$ROOT/build}"
JOBS="$(nproc 2>/dev/null || echo 2)"
FUZZ_SECONDS="${MOCAP_FUZZ_SECONDS:-60}"
PY=/usr/bin/python3
ALLOWED_SKIPS="$ROOT/scripts/allowed_skips.txt"

"$ROOT/scripts/setup.sh" || { echo "setup failed"; echo "0 passed, 1 failed, 0 skipped"; exit 1; }

total_passed=0
total_failed=0
total_skipped=0
summary=()

record() { # name passed failed skipped
  total_passed=$((total_passed + $2))
  total_failed=$((total_failed + $3))
  total_skipped=$((total_skipped + $4))
  summary+=("$(printf '%-28s %5d passed, %d failed, %d skipped' "$1" "$2" "$3" "$4")")
}

# A compile check: a unit that compiles is no test passed; one that does not is a failure.
record_units() { # name ok failed
  total_failed=$((total_failed + $3))
  summary+=("$(printf '%-28s %5d compile units ok, %d failed' "$1" "$2" "$3")")
}

# A whole suite that was not run on purpose (not for a missing dependency): one skip.
record_suite_skipped() { # name why
  total_skipped=$((total_skipped + 1))
  summary+=("$(printf '%-28s   suite skipped: %s' "$1" "$2")")
}

# Records a suite from its runner's results. kind: ctest (console log), pytest (JUnit XML from
# --junitxml), dotnet (TRX from --logger trx), counts (a "N passed, N failed[, N skipped]" line),
# units (a "N compile units ok, N failed" line). Unreadable results or no test run: one failure.
record_from() { # name kind file
  local counts
  counts="$("$PY" "$ROOT/scripts/test_results.py" --suite "$1" --allow "$ALLOWED_SKIPS" "$2" "$3")"
  if [ "$2" = units ]; then
    [[ "$counts" =~ ^[0-9]+\ [0-9]+$ ]] || counts="0 1"
    # shellcheck disable=SC2086
    record_units "$1" $counts
  else
    [[ "$counts" =~ ^[0-9]+\ [0-9]+\ [0-9]+$ ]] || counts="0 1 0"
    # shellcheck disable=SC2086
    record "$1" $counts
  fi
}

# Configures, builds and runs ctest in a build dir; a configure or build failure is one failure.
run_ctest_suite() { # name build_dir cmake_args... -- ctest_args...
  local name="$1" dir="$2"; shift 2
  local cmake_args=() ctest_args=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do cmake_args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  ctest_args=("$@")
  echo "=== $name: configure + build ($dir)"
  if ! cmake -S "$NATIVE" -B "$dir" "${cmake_args[@]}" >"$dir.configure.log" 2>&1; then
    cat "$dir.configure.log"; record "$name (configure)" 0 1 0; return
  fi
  if ! cmake --build "$dir" -j"$JOBS" >"$dir.build.log" 2>&1; then
    tail -50 "$dir.build.log"; record "$name (build)" 0 1 0; return
  fi
  echo "=== $name: ctest"
  local log="$dir.ctest.log"
  rm -f "$log"
  (cd "$dir" && ctest --output-on-failure -j"$JOBS" "${ctest_args[@]}") 2>&1 | tee "$log"
  record_from "$name" ctest "$log"
}

# pytest over some folders, results as JUnit XML (test names of the skips included).
run_pytest_suite() { # name results_stem paths...
  local name="$1" stem="$2"; shift 2
  rm -f "$stem.xml"
  (cd "$ROOT" && "$PY" -m pytest -q -rsx --junitxml="$stem.xml" "$@") 2>&1 | tee "$stem.log"
  record_from "$name" pytest "$stem.xml"
}

mkdir -p "$BUILD"
run_ctest_suite "engine (release)" "$BUILD/engine" -DCMAKE_BUILD_TYPE=RelWithDebInfo

if [ "${MOCAP_SKIP_SANITIZERS:-0}" = "1" ]; then
  for suite in "engine (asan+ubsan)" "engine threads (tsan)" "fuzz"; do
    record_suite_skipped "$suite" "MOCAP_SKIP_SANITIZERS=1"
  done
else
  run_ctest_suite "engine (asan+ubsan)" "$BUILD/engine-asan" -DCMAKE_BUILD_TYPE=Debug \
    -DMOCAP_SANITIZE=address,undefined
  run_ctest_suite "engine threads (tsan)" "$BUILD/engine-tsan" -DCMAKE_BUILD_TYPE=Debug \
    -DMOCAP_SANITIZE=thread -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -- -L threads

  # Three libFuzzer targets: the HiPNUC decoder (the bytes of every device) gets the full time,
  # the two file readers (capture files, calibration files) half of it each.
  fuzz_dir="$BUILD/fuzz"
  echo "=== fuzz: decoder ${FUZZ_SECONDS}s, capture and calibration file readers $((FUZZ_SECONDS / 2))s each"
  if CC=clang-14 CXX=clang++-14 cmake -S "$NATIVE" -B "$fuzz_dir" -DMOCAP_FUZZ=ON \
       -DMOCAP_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$fuzz_dir.log" 2>&1 &&
     cmake --build "$fuzz_dir" --target fuzz_hipnuc_decoder fuzz_capture_file fuzz_calibration_file \
       -j"$JOBS" >>"$fuzz_dir.log" 2>&1; then
    for target in hipnuc_decoder capture_file calibration_file; do
      seconds=$FUZZ_SECONDS
      [ "$target" = hipnuc_decoder ] || seconds=$((FUZZ_SECONDS / 2 > 0 ? FUZZ_SECONDS / 2 : 1))
      corpus="$fuzz_dir/corpus/$target"; mkdir -p "$corpus"
      log="$fuzz_dir.$target.run.log"
      artifacts="$fuzz_dir/artifacts/$target"; rm -rf "$artifacts"; mkdir -p "$artifacts"
      if (cd "$fuzz_dir" && "./fuzz/fuzz_$target" -max_total_time="$seconds" \
            -print_final_stats=1 -artifact_prefix="$artifacts/" \
            "$corpus" "$NATIVE/fuzz/corpus/$target") >"$log" 2>&1; then
        echo "  $target: $(grep -oE "number_of_executed_units: [0-9]+" "$log" || true)"
        record "fuzz ($target)" 1 0 0
      else
        tail -40 "$log"
        # A CI machine's files are gone after the run: print the failing input so it can be
        # rebuilt (base64 -d > input) and replayed with ./fuzz/fuzz_$target input.
        for input in "$artifacts"/*; do
          [ -f "$input" ] || continue
          echo "--- failing input $(basename "$input") ($(wc -c <"$input") bytes), base64:"
          head -c 8192 "$input" | base64
        done
        record "fuzz ($target)" 0 1 0
      fi
    done
  else
    tail -40 "$fuzz_dir.log"; record "fuzz (build)" 0 1 0
  fi
fi

# The engine on Windows for real: MinGW-w64 builds the DLL, mocapctl.exe and the GoogleTest
# suites, and ctest runs them under Wine with the Windows ONNX Runtime DLL (the golden pose test
# included). Missing MinGW-w64 or Wine is a failure, not a skip.
echo "=== engine: Windows (MinGW-w64 build, ctest under Wine)"
MOCAP_WINDOWS_BUILD_DIR="$BUILD/windows" JOBS="$JOBS" "$ROOT/scripts/test_windows.sh"
if [ -s "$BUILD/windows.ctest.log" ]; then
  record_from "engine (windows, wine)" ctest "$BUILD/windows.ctest.log"
else
  record "engine (windows, wine)" 0 1 0
fi
# The Windows plugin as it ships: Release DLL, only Windows' own imports, only mocap_* exports,
# loaded under Wine and opening the shipped model.
echo "=== Windows plugin: MinGW-w64 Release build, imports/exports, load under Wine"
if "$ROOT/scripts/build_windows_plugin.sh" 2>&1 | tee "$BUILD/windows-plugin.log"; then
  record "windows plugin (mingw-w64)" 1 0 0
else
  record "windows plugin (mingw-w64)" 0 1 0
fi

if [ -d "$ROOT/dotnet/Mocap.Imu.Core.Tests" ]; then
  echo "=== dotnet: C# core (NUnit) against the real engine"
  if ! command -v dotnet >/dev/null 2>&1; then
    echo "dotnet SDK not found"; record "dotnet (C# core)" 0 1 0
  else
    results="$BUILD/dotnet-results"
    rm -f "$results/core.trx"
    (cd "$ROOT" && MOCAP_MOCAPCTL="$BUILD/engine/mocapctl" \
      dotnet test dotnet/Mocap.Imu.Core.Tests -p:MocapNativeDir="$BUILD/engine" --nologo \
        --results-directory "$results" --logger "trx;LogFileName=core.trx") 2>&1 | tee "$BUILD/dotnet.log"
    record_from "dotnet (C# core)" dotnet "$results/core.trx"
  fi
fi

if ! command -v dotnet >/dev/null 2>&1; then
  echo "=== Unity compile gate: dotnet SDK not found"
  record_units "Unity compile gate" 0 1
else
  # Every asmdef and every sample alone, against a declaration-only Unity API, for Unity 2022.3
  # and Unity 6, in the editor and in the Windows / Linux / macOS players (warnings are errors).
  echo "=== Unity compile gate (2022.3 and 6000.0; editor and players; each sample alone)"
  log="$BUILD/compile-gate.log"
  (cd "$ROOT" && dotnet run --project dotnet/Mocap.Imu.CompileGate -- Packages/com.mocap.imu) 2>&1 | tee "$log"
  record_from "Unity compile gate" units "$log"
fi

echo "=== python: pytest training/"
run_pytest_suite "python (training)" "$BUILD/pytest-training" training/tests

# The Linux plugin as it ships: built in a Debian bullseye root (glibc 2.31, the oldest Linux
# Unity 2022.3 supports), replayed there and here, and no symbol may ask for a newer glibc.
echo "=== Linux plugin: glibc 2.31 build, replay on glibc 2.31 and here, symbol check"
if "$ROOT/scripts/build_native_plugin.sh" 2>&1 | tee "$BUILD/glibc-plugin.log"; then
  record "linux plugin (glibc 2.31 build)" 1 0 0
else
  record "linux plugin (glibc 2.31 build)" 0 1 0
fi
"$ROOT/scripts/check_glibc.sh" 2>&1 | tee "$BUILD/glibc.log"
record_from "linux plugin (glibc symbols)" counts "$BUILD/glibc.log"

echo "=== unity package: .meta files, package linter (pytest scripts/tests)"
"$PY" "$ROOT/scripts/package_lint.py" || true # the problems, file by file
MOCAP_MOCAPCTL="$BUILD/engine/mocapctl" run_pytest_suite "unity package (lint)" "$BUILD/pytest-scripts" \
  scripts/tests --ignore=scripts/tests/test_pose_accuracy.py

# The main job's pose accuracy on a generated capture, within bounds of today's figures; the
# same bounds must catch deliberately broken copies of the shipped model.
echo "=== pose accuracy: full-body replay through the shipped model (pytest)"
MOCAP_MOCAPCTL="$BUILD/engine/mocapctl" run_pytest_suite "pose accuracy" "$BUILD/pytest-accuracy" \
  scripts/tests/test_pose_accuracy.py

echo
echo "=== summary"
for line in "${summary[@]}"; do echo "$line"; done
echo "$total_passed passed, $total_failed failed, $total_skipped skipped"
[ "$total_failed" -eq 0 ]
