#!/usr/bin/env bash
# The main job on a fresh machine: install what is needed, build the engine, generate a 6-node
# HiPNUC capture of a known motion (calibration prelude + 22 s of walking, arm raises, squats and
# a turn, realistic sensor noise, ENU world with arbitrary per-sensor heading and mounting), and
# replay it through decode -> filter -> calibrate, printing a per-sensor summary and the error
# of the calibrated bone orientations against the generator's ground truth; then the same for a
# full-body motion through the pose model, writing a BVH and printing the pose accuracy.
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
  --world enu --noise realistic --seed 7
"$MOCAPCTL" replay "$OUT/demo.cap" --truth "$OUT/demo-truth.csv" \
  --save-calibration "$OUT/demo.calibration" --csv "$OUT/demo-frames.csv"
echo "outputs in $OUT: demo.cap (raw capture), demo-frames.csv (60 Hz calibrated frames), demo.calibration"

# The whole job with the pose model: a procedural full-body motion (training/procedural.py, 30 s:
# walk, arm swing, squat, turn) -> `training synth-capture` (sensor signals -> the same byte-level
# generator, with calibration prelude, random mountings and headings, realistic noise) -> replay
# through decode -> filter -> calibrate -> model -> drift correction with the shipped model ->
# BVH + accuracy against the pose truth (angle, position, root drift, jitter). About 2 s.
PY="${MOCAP_PYTHON:-/usr/bin/python3}"
[ -x "$PY" ] || PY=python3
(cd "$ROOT" && MOCAP_MOCAPCTL="$MOCAPCTL" "$PY" -c "
from training.procedural import make_motion
from training.synth_capture import synth_capture
m = make_motion('mixed', seconds=30, seed=7, name='procedural-mixed')
synth_capture(None, '$OUT/pose-demo.cap', motion=m, seed=7, world='enu')
")
"$MOCAPCTL" replay "$OUT/pose-demo.cap" --out "$OUT/demo.bvh" --json "$OUT/demo-poses.jsonl" \
  --truth "$OUT/pose-demo.truth.csv" --metrics-json "$OUT/demo-accuracy.json"
echo "pose outputs in $OUT: demo.bvh (SMPL-24, metres, 60 Hz; Blender: File > Import > BVH), demo-poses.jsonl,"
echo "  demo-accuracy.json (the accuracy figures above)"
