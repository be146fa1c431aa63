#!/usr/bin/env bash
# The main job on a fresh machine: install what is needed, build the engine, generate a 6-node
# HiPNUC capture of a known motion (calibration prelude + 30 s of walking, arm raises, squats and
# a turn, realistic sensor noise, ENU world with arbitrary per-sensor heading and mounting), and
# replay it through decode -> filter -> calibrate, printing a per-sensor summary and the error
# of the calibrated bone orientations against the generator's ground truth.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"

BUILD="$ROOT/build/main"
cmake -S "$ROOT/Packages/com.mocap.imu/Native~" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release \
  -DMOCAP_BUILD_TESTS=OFF >/dev/null
cmake --build "$BUILD" -j"$(nproc)" >/dev/null
MOCAPCTL="$BUILD/mocapctl"

OUT="$ROOT/out"
mkdir -p "$OUT"
"$MOCAPCTL" synth --out "$OUT/demo.cap" --truth "$OUT/demo-truth.csv" --motion mixed \
  --seconds 30 --world enu --noise realistic --seed 7
"$MOCAPCTL" replay "$OUT/demo.cap" --truth "$OUT/demo-truth.csv" \
  --save-calibration "$OUT/demo.calibration" --csv "$OUT/demo-frames.csv"
echo "outputs in $OUT: demo.cap (raw capture), demo-frames.csv (60 Hz calibrated frames), demo.calibration"
