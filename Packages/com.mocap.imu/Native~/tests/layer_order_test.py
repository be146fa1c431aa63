#!/usr/bin/env python3
"""Each layer of the engine includes only itself and the layers before it.

The order is CMakeLists.txt's MOCAP_LAYERS (the data flow: io -> protocol -> imu -> session ->
pose -> output, all over base). A file in src/<layer>/ may include the public header, its own
layer's headers and those of earlier layers; nothing in src/ may include the dev kit (devkit/),
which is not part of the plugin. Prints each offending include and exits 1, else a summary line.

Usage: layer_order_test.py NATIVE_DIR
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def layer_order(native: Path) -> list[str]:
    cmake = (native / "CMakeLists.txt").read_text(encoding="utf-8")
    m = re.search(r"set\(MOCAP_LAYERS\s+([^)]*)\)", cmake)
    if not m:
        sys.exit("layer_order_test: no set(MOCAP_LAYERS ...) in CMakeLists.txt")
    return m.group(1).split()


def main() -> int:
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[-1])
    native = Path(sys.argv[1])
    layers = layer_order(native)
    where: dict[str, str] = {}
    for layer in layers:
        folder = native / "src" / layer
        if not folder.is_dir():
            print(f"FAIL layer {layer} has no folder src/{layer}")
            return 1
        for header in [*folder.glob("*.h"), *folder.glob("*.def")]:
            where[header.name] = layer
    for header in (native / "devkit").glob("*.h"):
        where[header.name] = "devkit"
    public = {h.name for h in (native / "include").glob("*.h")}

    problems, checked = [], 0
    stray = [p for p in (native / "src").iterdir() if p.is_file() or p.name not in layers]
    problems += [f"src/{p.name} is in no layer" for p in stray]
    for rank, layer in enumerate(layers):
        for source in sorted((native / "src" / layer).glob("*.[ch]")):
            for name in INCLUDE.findall(source.read_text(encoding="utf-8")):
                checked += 1
                target = where.get(name)
                rel = source.relative_to(native).as_posix()
                if name in public:
                    continue
                if target is None:
                    if name != "onnxruntime_c_api.h":  # ONNX Runtime's header, beside the build
                        problems.append(f"{rel} includes {name}, found in no layer")
                elif target == "devkit":
                    problems.append(f"{rel} includes the dev kit's {name}")
                elif layers.index(target) > rank:
                    problems.append(f"{rel} ({layer}) includes {name} of the later layer {target}")
    for p in problems:
        print(f"FAIL {p}")
    print(f"{checked} includes in {len(layers)} layers checked, {len(problems)} out of order")
    return 1 if problems or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
