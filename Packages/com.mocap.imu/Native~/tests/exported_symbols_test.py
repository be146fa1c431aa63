#!/usr/bin/env python3
"""The plugin exports exactly the public header's functions and holds no dev-kit code.

Compares the functions the shared library exports (ELF dynamic symbols, or a DLL's export table)
with the MOCAP_API declarations of include/mocap_imu.h: a function missing from either side is a
failure, so a new API function cannot ship unexported and an internal one cannot leak. Then checks
that none of the dev kit's functions (the generator, the generic ONNX runner: every function the
dev-kit archive defines) was linked into the plugin.

Usage: exported_symbols_test.py --library LIB --header mocap_imu.h --devkit libmocap_devkit.a
                                [--tool-prefix x86_64-w64-mingw32-]
Exit status 0 when both hold; 1 naming every difference.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

DECLARATION = re.compile(r"\bMOCAP_API\b[^;{}()]*?\b(mocap_\w+)\s*\(")


def header_functions(header: Path) -> set[str]:
    text = header.read_text(encoding="utf-8")
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)  # comments mention MOCAP_API too
    text = re.sub(r"^\s*#.*$", " ", text, flags=re.M)   # so does the macro's definition
    return set(DECLARATION.findall(text))


def run(args: list[str]) -> str:
    try:
        done = subprocess.run(args, check=True, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit(f"exported_symbols_test: {args[0]} not found (binutils)")
    except subprocess.CalledProcessError as e:
        sys.exit(f"exported_symbols_test: {' '.join(args)} failed: {e.stderr.strip()}")
    return done.stdout


def exported_functions(library: Path, prefix: str) -> set[str]:
    if library.suffix.lower() == ".dll":
        # objdump -p prints the export table as "[ordinal] name" rows after "[Ordinal/Name Pointer] Table".
        table = run([f"{prefix}objdump", "-p", str(library)])
        start = table.find("[Ordinal/Name Pointer] Table")
        if start < 0:
            return set()
        names = set()
        for line in table[start:].splitlines()[1:]:
            m = re.match(r"\s*\[\s*\d+\]\s+(\S+)\s*$", line)
            if not m:
                break
            names.add(m.group(1))
        return names
    listing = run([f"{prefix}nm", "-D", "--defined-only", str(library)])
    # Reserved names ("__lsan_default_suppressions", a sanitizer build's hook) are no API.
    return {parts[2] for parts in (l.split() for l in listing.splitlines())
            if len(parts) == 3 and parts[1] in "TtWi" and not parts[2].startswith("__")}


def defined_functions(archive_or_binary: Path, prefix: str, kinds: str) -> set[str]:
    listing = run([f"{prefix}nm", "--defined-only", str(archive_or_binary)])
    return {parts[2] for parts in (l.split() for l in listing.splitlines())
            if len(parts) == 3 and parts[1] in kinds}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--library", type=Path, required=True)
    ap.add_argument("--header", type=Path, required=True)
    ap.add_argument("--devkit", type=Path, required=True)
    ap.add_argument("--tool-prefix", default="")
    args = ap.parse_args()

    declared = header_functions(args.header)
    exported = exported_functions(args.library, args.tool_prefix)
    problems = []
    if len(declared) < 10:
        problems.append(f"only {len(declared)} MOCAP_API functions found in {args.header}: the parser is off")
    for name in sorted(declared - exported):
        problems.append(f"declared in {args.header.name} but not exported: {name}")
    for name in sorted(exported - declared):
        problems.append(f"exported but not in {args.header.name}: {name}")

    # Its global functions: a file-local helper may share a name with one of the engine's.
    devkit = defined_functions(args.devkit, args.tool_prefix, "T")
    if not devkit:
        problems.append(f"{args.devkit} defines no function: not the dev-kit archive")
    # The plugin's own symbol table (not stripped in test builds) names every function it holds.
    leaked = devkit & defined_functions(args.library, args.tool_prefix, "Tt")
    for name in sorted(leaked):
        problems.append(f"dev-kit function linked into the plugin: {name}")

    for p in problems:
        print(f"FAIL {p}")
    print(f"{args.library.name}: {len(exported)} exported, {len(declared)} declared, "
          f"{len(devkit)} dev-kit functions checked absent")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
