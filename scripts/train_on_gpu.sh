#!/usr/bin/env bash
# Train on a CUDA machine that has the repository but not the motion data: the data travels as
# two motion packs (python3 -m training pack, ~28 MB for CMU's training + validation subjects).
#
#   here:  python3 -m training pack --split train --out packs/train.mpack
#          python3 -m training pack --split val --out packs/val.mpack
#   there: bash scripts/train_on_gpu.sh packs OUT MINUTES [train options...]
#
# Checks the CUDA path with a smoke run first (a broken setup fails in seconds, not after the
# data has loaded), trains warm-started from the shipped weights unless the options say
# otherwise, and leaves in OUT the weights-only best and last checkpoints (the committed form),
# the training log, the loss curve and the whole console output.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 PACK_DIR OUT_DIR MINUTES [train options...]" >&2; exit 2; }
packs=$1 out=$2 minutes=$3
device=${DEVICE:-cuda} py=${PYTHON:-python3}   # DEVICE=cpu: a dry run here
shift 3
cd "$(dirname "$0")/.."
export PYTHONPATH=. PYTHONUNBUFFERED=1
mkdir -p "$out"
exec > >(tee "$out/console.log") 2>&1
"$py" - <<'EOF'
import numpy, torch
print(f"torch {torch.__version__}, numpy {numpy.__version__}, cuda {torch.cuda.is_available()}"
      + (f", {torch.cuda.get_device_name(0)}" if torch.cuda.is_available() else ""))
EOF
work=$(mktemp -d)
"$py" -m training train --smoke --device "$device" --ckpt-dir "$work/smoke" --results-dir "$work/smoke"
workers=$(( $(nproc) > 2 ? $(nproc) - 2 : 1 ))
init=(--init-from training/checkpoints/mocap_pose.pt)
for a in "$@"; do [ "$a" = "--size" ] && init=(); done   # another size starts from scratch
"$py" -m training train --bvh "$packs/train.mpack" --val-bvh "$packs/val.mpack" --device "$device" \
    --data-workers "$workers" --budget-minutes "$minutes" "${init[@]}" \
    --ckpt-dir "$work/ckpt" --results-dir "$out" "$@"
"$py" - "$work/ckpt" "$out" <<'EOF'
import sys
from training.train import save_weights
for name in ("best", "last"):
    save_weights(f"{sys.argv[1]}/{name}.pt", f"{sys.argv[2]}/{name}.pt")
print("weights:", ", ".join(f"{sys.argv[2]}/{n}.pt" for n in ("best", "last")))
EOF
