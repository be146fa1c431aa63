#!/usr/bin/env python3
"""Writes the Unity .meta files of the com.mocap.imu package; never changes an existing GUID.

Every file and folder of the package gets a .meta (Unity ignores an asset without one, and an
installed package is read-only, so they must be committed), except:
  - the package root itself,
  - anything inside a folder whose name ends in "~" (Samples~, Documentation~, Native~: Unity
    does not import them),
  - hidden files and folders (".gitkeep", ".DS_Store": Unity ignores them),
  - .meta files themselves.

GUIDs: users' scenes and prefabs reference the package's scripts by GUID, so a GUID must survive
a move or a rename (done with its .meta, as Unity does). The GUID in a committed .meta is
therefore kept as it is, whatever the path; only an asset without a .meta gets a new GUID: the
first 32 hex digits of sha256("com.mocap.imu/" + its path), so that the build outputs' .meta
files (Runtime/Plugins, not committed) come out the same on every machine; when another .meta
already holds that GUID (an asset moved away from this path took it along), a random one
(uuid4, as Unity makes them) that no .meta of the package uses.

The importer follows the extension (see importer_for): MonoImporter (.cs),
AssemblyDefinitionImporter (.asmdef), PackageManifestImporter (the root package.json),
TextScriptImporter (.md .txt .json .xml .csv .bytes), PluginImporter with per-platform settings
(.so: Linux x86_64 editor + player; .dll: Windows x86_64; .dylib/.bundle: macOS), DefaultImporter
for folders and everything else, .onnx included (the native engine reads the model from its path;
Unity must not import it as a Sentis model). An existing .meta whose importer section differs is
rewritten with the generated importer and its own GUID.

Usage:
  scripts/unity_meta.py [--package DIR]           write missing .meta files, refresh importers,
                                                  delete orphans
  scripts/unity_meta.py [--package DIR] --check   change nothing; list every problem, exit 1 if any
A .meta without a well-formed GUID (32 lower-case hex digits) or with a GUID another .meta of the
package uses is reported in both modes and left alone: which asset keeps the GUID is a person's
call (the one scenes reference).
"""

import argparse
import hashlib
import os
import re
import sys
import uuid
from pathlib import Path

PACKAGE_NAME = "com.mocap.imu"
REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_PACKAGE = REPO_ROOT / "Packages" / PACKAGE_NAME

TEXT_EXTENSIONS = {".md", ".txt", ".json", ".xml", ".csv", ".bytes", ".yaml", ".yml"}
PLUGIN_EXTENSIONS = {".so", ".dll", ".dylib", ".bundle"}

_TAIL = "  userData: \n  assetBundleName: \n  assetBundleVariant: \n"


GUID_LINE = re.compile(r"^guid: *(\S*) *$", re.M)
WELL_FORMED_GUID = re.compile(r"[0-9a-f]{32}")


def new_guid(relpath: str, taken) -> str:
    """The GUID for a new asset at relpath: path-derived when free, else random; never in taken."""
    derived = hashlib.sha256(f"{PACKAGE_NAME}/{relpath}".encode("utf-8")).hexdigest()[:32]
    if derived not in taken:
        return derived
    while True:
        guid = uuid.uuid4().hex
        if guid not in taken:
            return guid


def guid_in(meta_text_: str):
    """The GUID written in a .meta's text, or None when it has no guid line."""
    found = GUID_LINE.search(meta_text_)
    return found.group(1) if found else None


def is_excluded_name(name: str) -> bool:
    """Names Unity never imports: hidden entries and ~ folders/files."""
    return name.startswith(".") or name.endswith("~")


def _plugin_platforms(ext: str):
    """(editor_os, editor_cpu, {player_platform: cpu}) for a native plugin extension."""
    if ext == ".so":
        return "Linux", "x86_64", {"Linux64": "x86_64"}
    if ext == ".dll":
        return "Windows", "x86_64", {"Win64": "x86_64"}
    # .dylib / .bundle: one universal (arm64 + x86_64) macOS library.
    return "OSX", "AnyCPU", {"OSXUniversal": "AnyCPU"}


def plugin_importer(ext: str) -> str:
    editor_os, editor_cpu, players = _plugin_platforms(ext)
    excludes = {
        "Android": 1, "Editor": 0, "Linux64": 0 if "Linux64" in players else 1,
        "OSXUniversal": 0 if "OSXUniversal" in players else 1, "Win": 1,
        "Win64": 0 if "Win64" in players else 1, "iOS": 1,
    }
    lines = [
        "PluginImporter:",
        "  externalObjects: {}",
        "  serializedVersion: 3",
        "  iconMap: {}",
        "  executionOrder: {}",
        "  defineConstraints: []",
        "  isPreloaded: 0",
        "  isOverridable: 0",
        "  isExplicitlyReferenced: 0",
        "  validateReferences: 1",
        "  platformData:",
        "    Any:",
        "      enabled: 0",
        "      settings:",
    ]
    lines += [f"        Exclude {k}: {v}" for k, v in sorted(excludes.items())]
    lines += [
        "    Editor:",
        "      enabled: 1",
        "      settings:",
        f"        CPU: {editor_cpu}",
        "        DefaultValueInitialized: true",
        f"        OS: {editor_os}",
    ]
    for platform in ("Linux64", "OSXUniversal", "Win", "Win64"):
        enabled = platform in players
        cpu = players.get(platform, "None")
        lines += [f"    {platform}:", f"      enabled: {1 if enabled else 0}", "      settings:",
                  f"        CPU: {cpu}"]
    return "\n".join(lines) + "\n" + _TAIL


def importer_for(relpath: str, is_dir: bool) -> str:
    """The importer section (everything after the guid line) of an asset's .meta."""
    if is_dir:
        return "folderAsset: yes\nDefaultImporter:\n  externalObjects: {}\n" + _TAIL
    name = relpath.rsplit("/", 1)[-1]
    ext = os.path.splitext(name)[1].lower()
    if ext == ".cs":
        return ("MonoImporter:\n  externalObjects: {}\n  serializedVersion: 2\n"
                "  defaultReferences: []\n  executionOrder: 0\n  icon: {instanceID: 0}\n" + _TAIL)
    if ext == ".asmdef" or ext == ".asmref":
        kind = "AssemblyDefinitionImporter" if ext == ".asmdef" else "AssemblyDefinitionReferenceImporter"
        return f"{kind}:\n  externalObjects: {{}}\n" + _TAIL
    if relpath == "package.json":
        return "PackageManifestImporter:\n  externalObjects: {}\n" + _TAIL
    if ext in TEXT_EXTENSIONS:
        return "TextScriptImporter:\n  externalObjects: {}\n" + _TAIL
    if ext in PLUGIN_EXTENSIONS:
        return plugin_importer(ext)
    # .onnx and anything else: imported as an opaque file. The engine loads the model from
    # Path.GetFullPath("Packages/com.mocap.imu/Runtime/Models/<name>.onnx").
    return "DefaultImporter:\n  externalObjects: {}\n" + _TAIL


def meta_text(relpath: str, is_dir: bool, guid: str) -> str:
    return f"fileFormatVersion: 2\nguid: {guid}\n" + importer_for(relpath, is_dir)


def walk_assets(package: Path):
    """Yields (relpath, is_dir) for every asset that needs a .meta, sorted, deterministic.
    A macOS .bundle is a folder that Unity treats as one asset: it is not descended into."""
    for dirpath, dirnames, filenames in os.walk(package):
        dirnames[:] = sorted(d for d in dirnames if not is_excluded_name(d))
        rel_dir = Path(dirpath).relative_to(package).as_posix()
        prefix = "" if rel_dir == "." else rel_dir + "/"
        for d in list(dirnames):
            if d.endswith(".bundle"):
                dirnames.remove(d)
                yield prefix + d, False
            else:
                yield prefix + d, True
        for f in sorted(filenames):
            if is_excluded_name(f) or f.endswith(".meta"):
                continue
            yield prefix + f, False


def walk_metas(package: Path):
    """Yields the relpath of every .meta file Unity would see (outside ~ and hidden folders)."""
    for dirpath, dirnames, filenames in os.walk(package):
        dirnames[:] = sorted(d for d in dirnames
                             if not is_excluded_name(d) and not d.endswith(".bundle"))
        rel_dir = Path(dirpath).relative_to(package).as_posix()
        prefix = "" if rel_dir == "." else rel_dir + "/"
        for f in sorted(filenames):
            if f.endswith(".meta") and not f.startswith("."):
                yield prefix + f


def read_guids(package: Path):
    """{meta relpath: GUID as written (None without a guid line)} for every .meta Unity sees."""
    return {m: guid_in((package / m).read_text(encoding="utf-8", errors="replace"))
            for m in walk_metas(package)}


def guid_problems(guids):
    """[(meta relpath, problem)] for malformed and duplicated GUIDs, in path order."""
    problems, first_owner = [], {}
    for m in sorted(guids):
        guid = guids[m]
        if guid is None or not WELL_FORMED_GUID.fullmatch(guid):
            problems.append((m, f"GUID {guid or '(none)'} is not 32 lower-case hex digits"))
        elif guid in first_owner:
            problems.append((m, f"duplicate GUID {guid} (also in {first_owner[guid]})"))
        else:
            first_owner[guid] = m
    return problems


def plan(package: Path):
    """Returns (missing, stale, orphans): lists of relpaths of .meta files. Stale: the importer
    section differs from the generated one (compared with the .meta's own GUID)."""
    missing, stale = [], []
    wanted = set()
    for rel, is_dir in walk_assets(package):
        meta_rel = rel + ".meta"
        wanted.add(meta_rel)
        meta_path = package / meta_rel
        if not meta_path.exists():
            missing.append(meta_rel)
            continue
        text = meta_path.read_text(encoding="utf-8", errors="replace")
        if text != meta_text(rel, is_dir, guid_in(text) or ""):
            stale.append(meta_rel)
    orphans = [m for m in walk_metas(package) if m not in wanted]
    return missing, stale, orphans


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--package", type=Path, default=DEFAULT_PACKAGE,
                    help="package root (default: %(default)s)")
    ap.add_argument("--check", action="store_true",
                    help="change nothing; report missing, stale and orphan .meta files")
    ap.add_argument("-q", "--quiet", action="store_true")
    args = ap.parse_args(argv)
    package = args.package.resolve()
    if not (package / "package.json").is_file():
        print(f"unity_meta: {package} has no package.json", file=sys.stderr)
        return 2

    missing, stale, orphans = plan(package)
    guids = read_guids(package)
    bad_guids = [(m, why) for m, why in guid_problems(guids) if m not in orphans]
    if args.check:
        for m in missing:
            print(f"{package / m[:-5]}: missing .meta file ({m})")
        for m in stale:
            print(f"{package / m}: importer settings differ from the generated ones; "
                  "run scripts/unity_meta.py")
        for m in orphans:
            print(f"{package / m}: orphan .meta (its asset {m[:-5]} does not exist)")
        for m, why in bad_guids:
            print(f"{package / m}: {why}")
        return 1 if (missing or stale or orphans or bad_guids) else 0

    assets = dict(walk_assets(package))
    for m in orphans:
        (package / m).unlink()
        if not args.quiet:
            print(f"removed orphan {m}")
    taken = {g for m, g in guids.items() if g and m not in orphans}
    for m in missing:
        guid = new_guid(m[:-5], taken)
        taken.add(guid)
        (package / m).write_text(meta_text(m[:-5], assets[m[:-5]], guid), encoding="utf-8",
                                 newline="\n")
        if not args.quiet:
            print(f"wrote {m}")
    for m in stale:
        kept = guids.get(m) or new_guid(m[:-5], taken)
        taken.add(kept)
        (package / m).write_text(meta_text(m[:-5], assets[m[:-5]], kept), encoding="utf-8",
                                 newline="\n")
        if not args.quiet:
            print(f"refreshed the importer of {m} "
                  f"({'GUID kept' if guids.get(m) else 'it had no GUID: a new one'})")
    bad_guids = [(m, why) for m, why in bad_guids if guids.get(m) is not None or m not in stale]
    for m, why in bad_guids:
        print(f"unity_meta: {package / m}: {why}; left as it is (fix it by hand)", file=sys.stderr)
    if not args.quiet:
        print(f"unity_meta: {len(missing)} written, {len(stale)} refreshed, "
              f"{len(orphans)} orphans removed, {len(assets)} assets in {package}")
    return 1 if bad_guids else 0


if __name__ == "__main__":
    sys.exit(main())
