#!/usr/bin/env bash
# Regenerates the capture fixture the package's PlayMode tests play
# (Packages/com.mocap.imu/Tests/Runtime/Fixtures/), deterministically: the engine's own
# `mocapctl synth` with a fixed motion, length and seed, then the capture header's wall-clock
# creation time set to 0 ("unknown" in docs/capture-format.md) with its CRC recomputed, so the
# bytes depend only on the engine's synthesiser.
#   scripts/make_test_fixtures.sh [OUT_DIR]      (default: the fixture folder in the package)
# mocapctl: $MOCAP_MOCAPCTL, else build/engine/mocapctl (scripts/test.sh builds it).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/Packages/com.mocap.imu/Tests/Runtime/Fixtures}"
MOCAPCTL="${MOCAP_MOCAPCTL:-$ROOT/build/engine/mocapctl}"
[ -x "$MOCAPCTL" ] || { echo "mocapctl not found at $MOCAPCTL: set MOCAP_MOCAPCTL or build the engine" >&2; exit 2; }
mkdir -p "$OUT"

# walk: 8 s synth prelude (heading 3 s, strapping 2 s, T-pose 3 s) then 4 s of walking.
"$MOCAPCTL" synth --out "$OUT/walk.cap" --truth "$OUT/walk.truth.csv" --motion walk --seconds 4 \
  --seed 3 --world nwu --noise realistic >/dev/null

python3 - "$OUT/walk.cap" <<'PY'
import struct, sys, zlib
path = sys.argv[1]
with open(path, "r+b") as f:
    head = bytearray(f.read(12))
    assert head[:8] == b"MOCAPRAW", "not a capture file"
    size = struct.unpack_from("<H", head, 10)[0]
    f.seek(0)
    header = bytearray(f.read(size))
    struct.pack_into("<q", header, 16, 0)                      # created_ns: unknown
    struct.pack_into("<I", header, size - 4, zlib.crc32(bytes(header[:size - 4])) & 0xFFFFFFFF)
    f.seek(0)
    f.write(header)
PY
echo "wrote $OUT/walk.cap and $OUT/walk.truth.csv"
