#!/usr/bin/env bash
# Runs every test suite of the project and ends with one line "N passed, N failed".
#   engine:       ctest on a normal build, an ASan+UBSan build and (threading suites) a TSan build
#   fuzz:         the HiPNUC decoder and the capture / calibration file readers under
#                 libFuzzer for a bounded time
#   windows:      every engine source cross-compiled for Windows (MinGW-w64, syntax + warnings)
#   dotnet:       the C# core's NUnit tests against the real native library, and a C# 9 syntax
#                 check of every file of the Unity package (the Unity glue cannot be compiled here),
#                 which also fails a component or settings field shown in the inspector without a tooltip
#   python:       pytest over training/ (when it has tests)
#   unity package: pytest over scripts/tests (.meta generator and package linter, incl. a lint
#                 of the real package: run scripts/unity_meta.py after adding files)
# Environment: MOCAP_FUZZ_SECONDS (default 60), MOCAP_SKIP_SANITIZERS=1 for a quick local run.
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
NATIVE="$ROOT/Packages/com.mocap.imu/Native~"
BUILD="$ROOT/build"
JOBS="$(nproc 2>/dev/null || echo 2)"
FUZZ_SECONDS="${MOCAP_FUZZ_SECONDS:-60}"

"$ROOT/scripts/setup.sh" || { echo "setup failed"; echo "0 passed, 1 failed"; exit 1; }

total_passed=0
total_failed=0
summary=()

record() { # name passed failed
  total_passed=$((total_passed + $2))
  total_failed=$((total_failed + $3))
  summary+=("$(printf '%-28s %5d passed, %d failed' "$1" "$2" "$3")")
}

# Runs ctest in a build dir and records its counts; a build failure counts as one failure.
run_ctest_suite() { # name build_dir cmake_args... -- ctest_args...
  local name="$1" dir="$2"; shift 2
  local cmake_args=() ctest_args=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do cmake_args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  ctest_args=("$@")
  echo "=== $name: configure + build ($dir)"
  if ! cmake -S "$NATIVE" -B "$dir" "${cmake_args[@]}" >"$dir.configure.log" 2>&1; then
    cat "$dir.configure.log"; record "$name (configure)" 0 1; return
  fi
  if ! cmake --build "$dir" -j"$JOBS" >"$dir.build.log" 2>&1; then
    tail -50 "$dir.build.log"; record "$name (build)" 0 1; return
  fi
  echo "=== $name: ctest"
  local log="$dir.ctest.log"
  (cd "$dir" && ctest --output-on-failure -j"$JOBS" "${ctest_args[@]}") 2>&1 | tee "$log"
  local line failed total
  line="$(grep -E 'tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -1)"
  if [ -z "$line" ]; then
    if grep -q "No tests were found" "$log"; then record "$name" 0 1; else record "$name" 0 1; fi
    return
  fi
  failed="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"$line")"
  total="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\2/' <<<"$line")"
  record "$name" $((total - failed)) "$failed"
}

mkdir -p "$BUILD"
run_ctest_suite "engine (release)" "$BUILD/engine" -DCMAKE_BUILD_TYPE=RelWithDebInfo

if [ "${MOCAP_SKIP_SANITIZERS:-0}" != "1" ]; then
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
        record "fuzz ($target)" 1 0
      else
        tail -40 "$log"
        # A CI machine's files are gone after the run: print the failing input so it can be
        # rebuilt (base64 -d > input) and replayed with ./fuzz/fuzz_$target input.
        for input in "$artifacts"/*; do
          [ -f "$input" ] || continue
          echo "--- failing input $(basename "$input") ($(wc -c <"$input") bytes), base64:"
          head -c 8192 "$input" | base64
        done
        record "fuzz ($target)" 0 1
      fi
    done
  else
    tail -40 "$fuzz_dir.log"; record "fuzz (build)" 0 1
  fi
fi

# The engine must compile on Windows (Win32 serial, Winsock, LoadLibrary): every source of the
# library, as CMake lists them, through MinGW-w64 with warnings as errors (syntax and types; no
# link, no run: there is no Windows here).
if command -v x86_64-w64-mingw32-gcc >/dev/null 2>&1; then
  echo "=== engine: Windows cross-compile check (MinGW-w64, -Werror)"
  win_pass=0; win_fail=0
  for src in $(grep -oE 'src/[a-z_0-9]+\.c' "$NATIVE/CMakeLists.txt" | sort -u | grep -v posix); do
    if out="$(x86_64-w64-mingw32-gcc -std=c11 -Wall -Wextra -Wno-unused-parameter -Werror -fsyntax-only \
        -D__USE_MINGW_ANSI_STDIO=1 -DMOCAP_BUILDING_LIBRARY -DMOCAP_HAVE_ONNXRUNTIME=1 \
        -I"$NATIVE/include" -I"$NATIVE/src" -I"$ROOT/build/third_party/onnxruntime/include" \
        "$NATIVE/$src" 2>&1)" && [ -z "$out" ]; then
      win_pass=$((win_pass + 1))
    else
      win_fail=$((win_fail + 1)); echo "$src:"; echo "$out" | head -20
    fi
  done
  echo "$win_pass sources compile for Windows, $win_fail do not"
  record "engine (Windows compile)" "$win_pass" "$win_fail"
else
  echo "x86_64-w64-mingw32-gcc not found"; record "engine (Windows compile)" 0 1
fi

if [ -d "$ROOT/dotnet/Mocap.Imu.Core.Tests" ]; then
  echo "=== dotnet: C# core (NUnit) against the real engine"
  log="$BUILD/dotnet.log"
  if ! command -v dotnet >/dev/null 2>&1; then
    echo "dotnet SDK not found"; record "dotnet (C# core)" 0 1
  else
    (cd "$ROOT" && MOCAP_MOCAPCTL="$BUILD/engine/mocapctl" \
      dotnet test dotnet/Mocap.Imu.Core.Tests -p:MocapNativeDir="$BUILD/engine" --nologo) 2>&1 | tee "$log"
    line="$(grep -E '(Passed|Failed)! +- +Failed: +[0-9]+, +Passed: +[0-9]+' "$log" | tail -1)"
    if [ -z "$line" ]; then
      record "dotnet (C# core)" 0 1
    else
      f="$(sed -E 's/.*Failed: +([0-9]+),.*/\1/' <<<"$line")"
      p="$(sed -E 's/.*Passed: +([0-9]+),.*/\1/' <<<"$line")"
      record "dotnet (C# core)" "$p" "$f"
    fi
  fi
fi

if [ -d "$ROOT/dotnet/Mocap.Imu.SyntaxCheck" ] && ! command -v dotnet >/dev/null 2>&1; then
  echo "=== C# syntax of the whole Unity package: dotnet SDK not found"
  record "C# syntax (Unity package)" 0 1
elif [ -d "$ROOT/dotnet/Mocap.Imu.SyntaxCheck" ]; then
  # The Unity glue cannot be compiled here (no UnityEngine assemblies): parse all of it instead.
  echo "=== C# syntax of the whole Unity package (C# 9, editor and player symbols)"
  log="$BUILD/syntax.log"
  (cd "$ROOT" && dotnet run --project dotnet/Mocap.Imu.SyntaxCheck -- Packages/com.mocap.imu) 2>&1 | tee "$log"
  line="$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -1)"
  if [ -z "$line" ]; then
    record "C# syntax (Unity package)" 0 1
  else
    record "C# syntax (Unity package)" "$(cut -d' ' -f1 <<<"$line")" "$(cut -d' ' -f3 <<<"$line")"
  fi
fi

if [ -d "$ROOT/training/tests" ]; then
  echo "=== python: pytest training/"
  log="$BUILD/pytest.log"
  (cd "$ROOT" && /usr/bin/python3 -m pytest -q training/tests) 2>&1 | tee "$log"
  p="$(grep -Eo '[0-9]+ passed' "$log" | tail -1 | grep -Eo '[0-9]+' || echo 0)"
  f="$(grep -Eo '[0-9]+ (failed|error)' "$log" | awk '{s+=$1} END {print s+0}')"
  if [ "$p" = "0" ] && [ "$f" = "0" ]; then f=1; fi
  record "python (training)" "$p" "$f"
fi

if [ -d "$ROOT/scripts/tests" ]; then
  echo "=== unity package: .meta files, package linter (pytest scripts/tests)"
  /usr/bin/python3 "$ROOT/scripts/package_lint.py" || true # the problems, file by file
  log="$BUILD/pytest-scripts.log"
  (cd "$ROOT" && /usr/bin/python3 -m pytest -q scripts/tests) 2>&1 | tee "$log"
  p="$(grep -Eo '[0-9]+ passed' "$log" | tail -1 | grep -Eo '[0-9]+' || echo 0)"
  f="$(grep -Eo '[0-9]+ (failed|error)' "$log" | awk '{s+=$1} END {print s+0}')"
  if [ "$p" = "0" ] && [ "$f" = "0" ]; then f=1; fi
  record "unity package (lint)" "$p" "$f"
fi

echo
echo "=== summary"
for line in "${summary[@]}"; do echo "$line"; done
echo "$total_passed passed, $total_failed failed"
[ "$total_failed" -eq 0 ]
