#!/usr/bin/env bash
# Cross-validation over subject folds on a lent CUDA machine that has the repository but not the
# motion data (the data travels as the two motion packs train_on_gpu.sh describes).
#
#   there: bash scripts/cv_on_gpu.sh PACK_DIR OUT_DIR SECONDS [recipe options...]
#          STEPS=N bash scripts/cv_on_gpu.sh ...    # a known pace: N steps per fold, no probe
#
# A lease is short and fixed, so the step count every fold trains is fixed here from a measured
# pace: a probe trains every fold at once for a few steps (through the same cv command, so a
# broken setup fails in the first minute), the slowest fold's time per step sets how many steps
# fit in what is left of SECONDS, and then all folds train that many steps at once, each with its
# share of the cores for synthesis (the pace is set by synthesis on the CPU, not by the GPU: an
# H200 machine's 16 cores, 3 synthesis workers per fold, gave 0.44 s per step of 256 x 120 frames,
# 0.37 s of it waiting for data). OUT_DIR receives cv.md, cv.json, the console output and
# folds.tar.gz (each fold's row, console, training log and evaluation), the last even when the
# run is cut short.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 PACK_DIR OUT_DIR SECONDS [recipe options...]" >&2; exit 2; }
packs=$(cd "$1" && pwd) seconds=$3
mkdir -p "$2" && out=$(cd "$2" && pwd)
device=${DEVICE:-cuda} py=${PYTHON:-python3}   # DEVICE=cpu: a dry run here
folds=${FOLDS:-4} probe_steps=${PROBE_STEPS:-25}
eval_seconds=${EVAL_SECONDS:-60}       # the first S seconds of each held-out clip are scored
reserve=${RESERVE_SECONDS:-100}        # after training: the last inner validation, scoring, report
shift 3
cd "$(dirname "$0")/.."
export PYTHONPATH=. PYTHONUNBUFFERED=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec > >(tee "$out/console.log") 2>&1
start=$(date +%s)
"$py" - <<'EOF'
import numpy, torch
print(f"torch {torch.__version__}, numpy {numpy.__version__}, cuda {torch.cuda.is_available()}"
      + (f", {torch.cuda.get_device_name(0)}" if torch.cuda.is_available() else ""))
EOF
# the cores, not nproc: nproc answers OMP_NUM_THREADS, set to 1 above
cores=$("$py" -c "import os; print(len(os.sched_getaffinity(0)))")
workers=${WORKERS:-$(( (cores - folds) / folds ))}; [ "$workers" -ge 1 ] || workers=1
work=$(mktemp -d)
common=(--packs "$packs" --folds "$folds" --jobs "$folds" --device "$device" --data-workers "$workers"
        --eval-max-seconds "$eval_seconds" --eval-every 120)

collect() {   # one archive: the lease brings back a handful of files
    [ -d "$work/runs" ] && tar -czf "$out/folds.tar.gz" -C "$work/runs" \
        $(cd "$work/runs" && ls -d fold*/row.json fold*/console.log fold*/results/train_log.json \
          fold*/eval/evaluation.md 2>/dev/null)
    return 0
}
trap collect EXIT

if [ -n "${STEPS:-}" ]; then   # the pace is known from an earlier lease: no probe
    steps=$STEPS
    echo "cv_on_gpu: $STEPS steps per fold, $workers data workers each (no probe)"
else
    echo "cv_on_gpu: probe: $folds folds at once, $probe_steps steps each, $workers data workers each"
    # scored on 12 s per clip: enough for a 10 s drift window, little time
    "$py" -m training cv "${common[@]}" --steps "$probe_steps" --runs "$work/probe" \
        --out "$work/probe-report" --eval-max-seconds 12 "$@"
    per_step=$("$py" - "$work/probe" "$folds" <<'EOF'
import json, sys
from pathlib import Path
paces = [json.loads((Path(sys.argv[1]) / f"fold{n}" / "results" / "train_log.json").read_text())
         ["summary"]["s_per_step_median"] for n in range(1, int(sys.argv[2]) + 1)]
print(max(paces))
EOF
)
    left=$(( seconds - ($(date +%s) - start) - reserve ))
    steps=$("$py" -c "print(max(1, int($left / ($per_step * 1.08))))")
    echo "cv_on_gpu: slowest fold $per_step s/step; $left s left for training -> $steps steps per fold"
fi
"$py" -m training cv "${common[@]}" --steps "$steps" --runs "$work/runs" --out "$out" "$@"
echo "cv_on_gpu: done in $(( $(date +%s) - start )) s"
