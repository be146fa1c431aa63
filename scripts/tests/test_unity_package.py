"""Tests of scripts/unity_meta.py (.meta generation that never changes a GUID) and
scripts/package_lint.py.

The linter must pass on the real package and fail, naming the file, on damaged copies."""

import hashlib
import json
import re
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parent.parent
REPO = SCRIPTS.parent
REAL_PACKAGE = REPO / "Packages" / "com.mocap.imu"
sys.path.insert(0, str(SCRIPTS))

import package_lint  # noqa: E402
import unity_meta  # noqa: E402


def _copy_fn(src, dst):
    # The models are never modified by a test: link them (fast); copy everything else.
    if src.endswith(".onnx"):
        try:
            os.link(src, dst)
            return dst
        except OSError:
            pass
    return shutil.copy2(src, dst)


def _ignore(directory, names):
    rel = Path(directory).resolve().relative_to(REAL_PACKAGE.resolve()).as_posix()
    skip = {"Native~"} if rel == "." else set()
    if rel == "Runtime":  # local build outputs (git-ignored) must not influence the tests
        skip |= {"Plugins", "Plugins.meta"}
    return [n for n in names if n in skip or n == "__pycache__"]


@pytest.fixture
def pkg(tmp_path):
    """A copy of the real package (without Native~ and built plugins) in a fresh folder."""
    dest = tmp_path / "com.mocap.imu"
    shutil.copytree(REAL_PACKAGE, dest, ignore=_ignore, copy_function=_copy_fn)
    # Files added since the last generator run (other work in progress) get their .meta here, so
    # that each damage test sees exactly its own damage; the real package is checked separately.
    unity_meta.main(["--package", str(dest), "-q"])
    return dest


def lint(path):
    return package_lint.lint(path, use_git=False)


def problems_about(problems, rel, text):
    return [p for p in problems if rel in p and text in p]


def meta_files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*.meta"))}


def guid_of(root, rel):
    """The GUID written in the .meta of asset rel."""
    return unity_meta.guid_in((root / (rel + ".meta")).read_text())


def edit_json(path, **changes):
    data = json.loads(path.read_text()) if path.exists() else {}
    data.update(changes)
    path.write_text(json.dumps(data, indent=4))
    return data


def add_plugin(pkg, rel, content=b"\x7fELF fake"):
    path = pkg / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(content)
    return path


# ------------------------------------------------------------------------------ the generator

def test_a_new_guid_is_path_derived_unless_taken():
    derived = hashlib.sha256(b"com.mocap.imu/Runtime/Plugins/Linux/x86_64/libmocap_imu.so")
    rel = "Runtime/Plugins/Linux/x86_64/libmocap_imu.so"
    assert unity_meta.new_guid(rel, set()) == derived.hexdigest()[:32]
    assert unity_meta.new_guid("Runtime", set()) != unity_meta.new_guid("Runtime/", set())
    # Taken (a moved asset kept it): random, well-formed, and different every time.
    taken = {derived.hexdigest()[:32]}
    randoms = {unity_meta.new_guid(rel, taken) for _ in range(1000)}
    assert len(randoms) == 1000 and not randoms & taken
    assert all(re.fullmatch(r"[0-9a-f]{32}", g) for g in randoms)


def test_plugin_metas_are_the_same_on_every_machine(tmp_path, pkg):
    other = tmp_path / "elsewhere" / "com.mocap.imu"
    shutil.copytree(pkg, other, copy_function=_copy_fn)
    for root in (pkg, other):
        add_plugin(root, "Runtime/Plugins/Linux/x86_64/libmocap_imu.so")
        assert unity_meta.main(["--package", str(root), "-q"]) == 0
    first, second = meta_files(pkg), meta_files(other)
    assert [m for m in first if m.startswith("Runtime/Plugins")] and first == second


def test_committed_metas_match_the_generator():
    missing, stale, orphans = unity_meta.plan(REAL_PACKAGE)
    assert (missing, stale, orphans) == ([], [], []), \
        "run `python3 scripts/unity_meta.py` (missing/stale/orphan .meta files)"


def test_regenerating_keeps_every_committed_guid(pkg):
    before = meta_files(pkg)
    assert unity_meta.main(["--package", str(pkg), "-q"]) == 0
    assert meta_files(pkg) == before
    committed = {k: v for k, v in meta_files(REAL_PACKAGE).items()
                 if not k.startswith("Runtime/Plugins") and not k.startswith("Native~")}
    assert len(committed) > 50
    assert {k: before.get(k) for k in committed} == committed


def test_only_an_asset_without_a_meta_gets_a_new_guid(pkg):
    rel = "Runtime/Core/MocapEngine.cs"
    (pkg / (rel + ".meta")).unlink()
    new_file = pkg / "Runtime/Core/NewThing.cs"
    new_file.write_text("namespace Mocap.Imu { class NewThing {} }\n")
    others = {m: g for m, g in unity_meta.read_guids(pkg).items()}
    assert unity_meta.main(["--package", str(pkg), "-q"]) == 0
    fresh = guid_of(pkg, rel), guid_of(pkg, "Runtime/Core/NewThing.cs")
    assert all(re.fullmatch(r"[0-9a-f]{32}", g) for g in fresh)
    assert fresh[0] != fresh[1]
    assert not set(fresh) & set(others.values())
    assert {m: g for m, g in unity_meta.read_guids(pkg).items() if m in others} == others
    assert lint(pkg) == []


def test_refreshing_an_importer_keeps_a_guid_that_is_not_the_path_hash(pkg):
    meta = pkg / "Runtime/Core/MocapEngine.cs.meta"
    chosen = "0123456789abcdef0123456789abcdef"
    meta.write_text(unity_meta.meta_text("Runtime/Core/MocapEngine.cs", False, chosen)
                    .replace("executionOrder: 0", "executionOrder: 100"))
    assert unity_meta.main(["--package", str(pkg), "-q"]) == 0
    assert meta.read_text() == unity_meta.meta_text("Runtime/Core/MocapEngine.cs", False, chosen)


@pytest.mark.parametrize("old,new", [
    ("Runtime/Core/MocapEngine.cs", "Runtime/Core/Engine/MocapEngineMoved.cs"),
    ("Runtime/Core/Maths", "Runtime/Core/Mathematics"),
    ("Runtime/HumanoidPoseDriver.cs", "Runtime/HumanoidPoseDriverRenamed.cs"),
])
def test_a_moved_or_renamed_asset_keeps_its_guid(pkg, old, new):
    guid = guid_of(pkg, old)
    target = pkg / new
    target.parent.mkdir(parents=True, exist_ok=True)
    (pkg / old).rename(target)
    (pkg / (old + ".meta")).rename(pkg / (new + ".meta"))
    unity_meta.main(["--package", str(pkg), "-q"])  # a new folder gets its own .meta
    assert lint(pkg) == []
    assert unity_meta.main(["--package", str(pkg), "--check"]) == 0
    assert guid_of(pkg, new) == guid
    # A new asset at the old path is another asset: it must not take the moved one's GUID.
    if (pkg / new).is_file():
        (pkg / old).write_text("// another file\n")
        unity_meta.main(["--package", str(pkg), "-q"])
        assert guid_of(pkg, old) != guid
        assert lint(pkg) == []


def test_generator_is_idempotent(pkg, capsys):
    add_plugin(pkg, "Runtime/Plugins/Linux/x86_64/libx.so")
    assert unity_meta.main(["--package", str(pkg)]) == 0
    before = meta_files(pkg)
    stamps = {p: p.stat().st_mtime_ns for p in pkg.rglob("*.meta")}
    capsys.readouterr()
    assert unity_meta.main(["--package", str(pkg)]) == 0
    out = capsys.readouterr().out
    assert "0 written, 0 refreshed, 0 orphans removed" in out
    assert meta_files(pkg) == before
    assert {p: p.stat().st_mtime_ns for p in pkg.rglob("*.meta")} == stamps
    assert unity_meta.main(["--package", str(pkg), "--check"]) == 0


def test_generator_skips_tilde_folders_and_dot_files(pkg):
    (pkg / "Samples~" / "Demo").mkdir(parents=True)
    (pkg / "Samples~" / "Demo" / "Demo.cs").write_text("class Demo {}\n")
    (pkg / "Runtime" / ".hidden").write_text("x")
    (pkg / "Runtime" / "Notes~").mkdir()
    (pkg / "Runtime" / "Notes~" / "a.txt").write_text("x")
    unity_meta.main(["--package", str(pkg), "-q"])
    metas = meta_files(pkg)
    assert not [m for m in metas if "~" in m]
    assert "Runtime/.hidden.meta" not in metas
    assert "Runtime/Notes~.meta" not in metas
    assert "package.json.meta" in metas and "Runtime.meta" in metas
    assert ".meta" not in metas  # the package root itself has none


@pytest.mark.parametrize("rel,is_dir,needle", [
    ("Runtime", True, "folderAsset: yes\nDefaultImporter:"),
    ("Runtime/Core/MocapEngine.cs", False, "MonoImporter:\n  externalObjects: {}\n  serializedVersion: 2"),
    ("Runtime/Mocap.Imu.asmdef", False, "AssemblyDefinitionImporter:"),
    ("package.json", False, "PackageManifestImporter:"),
    ("CHANGELOG.md", False, "TextScriptImporter:"),
    ("Runtime/Models/MODEL_CARD.md", False, "TextScriptImporter:"),
    ("Runtime/Models/mocap_pose_fp32.onnx", False, "DefaultImporter:"),
    ("LICENSE", False, "DefaultImporter:"),
])
def test_importer_per_kind(rel, is_dir, needle):
    guid = unity_meta.new_guid(rel, set())
    text = unity_meta.meta_text(rel, is_dir, guid)
    assert text.startswith(f"fileFormatVersion: 2\nguid: {guid}\n")
    assert needle in text
    assert ("folderAsset: yes" in text) == is_dir


@pytest.mark.parametrize("rel,editor_os,player", [
    ("Runtime/Plugins/Linux/x86_64/libmocap_imu.so", "Linux", "Linux64"),
    ("Runtime/Plugins/Windows/x86_64/mocap_imu.dll", "Windows", "Win64"),
    ("Runtime/Plugins/macOS/libmocap_imu.dylib", "OSX", "OSXUniversal"),
    ("Runtime/Plugins/macOS/mocap_imu.bundle", "OSX", "OSXUniversal"),
])
def test_plugin_meta_enables_its_platform_only(rel, editor_os, player):
    tree = package_lint.parse_meta(unity_meta.meta_text(rel, False, "1" * 32))
    pdata = tree["PluginImporter"]["platformData"]
    enabled = {k for k, v in pdata.items() if v.get("enabled") == "1"}
    assert enabled == {"Editor", player}
    assert pdata["Editor"]["settings"]["OS"] == editor_os
    assert pdata["Any"]["settings"][f"Exclude {player}"] == "0"


def test_generator_removes_orphans_and_check_lists_them(pkg, capsys):
    orphan = pkg / "Runtime" / "Gone.cs.meta"
    orphan.write_text(unity_meta.meta_text("Runtime/Gone.cs", False, "2" * 32))
    (pkg / "Runtime" / "Core" / "MocapEngine.cs.meta").unlink()
    assert unity_meta.main(["--package", str(pkg), "--check"]) == 1
    out = capsys.readouterr().out
    assert "Runtime/Gone.cs.meta: orphan .meta" in out
    assert "Runtime/Core/MocapEngine.cs: missing .meta file" in out
    assert orphan.exists()  # --check changes nothing
    assert not (pkg / "Runtime" / "Core" / "MocapEngine.cs.meta").exists()
    assert unity_meta.main(["--package", str(pkg), "-q"]) == 0
    assert not orphan.exists()
    assert (pkg / "Runtime" / "Core" / "MocapEngine.cs.meta").exists()


def test_bundle_folder_is_one_plugin_asset(pkg):
    (pkg / "Runtime/Plugins/macOS/mocap_imu.bundle/Contents/MacOS").mkdir(parents=True)
    (pkg / "Runtime/Plugins/macOS/mocap_imu.bundle/Contents/MacOS/mocap_imu").write_bytes(b"x")
    unity_meta.main(["--package", str(pkg), "-q"])
    metas = meta_files(pkg)
    assert b"PluginImporter" in metas["Runtime/Plugins/macOS/mocap_imu.bundle.meta"]
    assert not [m for m in metas if "mocap_imu.bundle/" in m]
    assert lint(pkg) == []


# -------------------------------------------------------------------------------- the linter

def test_linter_passes_on_the_real_package():
    assert package_lint.lint(REAL_PACKAGE, use_git=True) == []


def test_linter_passes_on_a_clean_copy_with_plugins(pkg):
    for rel in ("Runtime/Plugins/Linux/x86_64/libmocap_imu.so",
                "Runtime/Plugins/Windows/x86_64/mocap_imu.dll",
                "Runtime/Plugins/macOS/libmocap_imu.dylib"):
        add_plugin(pkg, rel)
    unity_meta.main(["--package", str(pkg), "-q"])
    assert lint(pkg) == []


def test_missing_meta_names_the_file(pkg):
    (pkg / "Runtime/Core/MocapEngine.cs.meta").unlink()
    (pkg / "Runtime/Core/Maths.meta").unlink()
    problems = lint(pkg)
    assert problems_about(problems, "Runtime/Core/MocapEngine.cs:", "has no .meta file")
    assert problems_about(problems, "Runtime/Core/Maths:", "has no .meta file")
    assert len(problems) == 2


def test_new_file_without_meta_is_reported(pkg):
    (pkg / "Runtime/Core/NewThing.cs").write_text("namespace Mocap.Imu { class NewThing {} }\n")
    problems = lint(pkg)
    assert problems == [f"{pkg / 'Runtime/Core/NewThing.cs'}: has no .meta file "
                        "(expected Runtime/Core/NewThing.cs.meta; run scripts/unity_meta.py)"]


def test_orphan_meta(pkg):
    (pkg / "Runtime/Deleted.cs.meta").write_text(
        unity_meta.meta_text("Runtime/Deleted.cs", False, "3" * 32))
    assert problems_about(lint(pkg), "Runtime/Deleted.cs.meta", "orphan .meta")


def test_orphan_plugin_meta_without_binary(pkg):
    so = add_plugin(pkg, "Runtime/Plugins/Linux/x86_64/libmocap_imu.so")
    unity_meta.main(["--package", str(pkg), "-q"])
    so.unlink()
    assert problems_about(lint(pkg), "libmocap_imu.so.meta", "orphan .meta")


def test_duplicated_guid(pkg):
    a = pkg / "Runtime/Core/MocapEngine.cs.meta"
    b = pkg / "Runtime/Core/MocapSession.cs.meta"
    guid_a = guid_of(pkg, "Runtime/Core/MocapEngine.cs")
    b.write_text(b.read_text().replace(guid_of(pkg, "Runtime/Core/MocapSession.cs"), guid_a))
    problems = lint(pkg)
    assert len(problems) == 1, problems
    assert "duplicate GUID " + guid_a in problems[0]
    assert "MocapEngine.cs.meta" in problems[0] and "MocapSession.cs.meta" in problems[0]
    # The generator cannot know which asset scenes reference: it reports and changes nothing.
    before = meta_files(pkg)
    assert unity_meta.main(["--package", str(pkg), "-q"]) == 1
    assert meta_files(pkg) == before and a.exists()


@pytest.mark.parametrize("bad", [
    "0123456789ABCDEF0123456789ABCDEF",  # upper case: Unity writes lower case
    "0123456789abcdef",                  # too short
    "0123456789abcdef0123456789abcdeg",  # not hex
    "",
])
def test_malformed_guid(pkg, bad):
    meta = pkg / "Runtime/Core/MocapEngine.cs.meta"
    meta.write_text(unity_meta.meta_text("Runtime/Core/MocapEngine.cs", False, bad))
    problems = lint(pkg)
    assert problems_about(problems, "MocapEngine.cs.meta", "is not 32 lower-case hex digits")
    assert unity_meta.main(["--package", str(pkg), "--check"]) == 1


def test_meta_without_a_guid_line(pkg):
    meta = pkg / "Runtime/Core/MocapEngine.cs.meta"
    meta.write_text(re.sub(r"^guid:.*\n", "", meta.read_text(), flags=re.M))
    assert problems_about(lint(pkg), "MocapEngine.cs.meta", "GUID (none)")


def test_hand_edited_importer_is_stale(pkg):
    m = pkg / "Runtime/Core/MocapEngine.cs.meta"
    m.write_text(m.read_text().replace("executionOrder: 0", "executionOrder: 100"))
    assert problems_about(lint(pkg), "MocapEngine.cs.meta", "importer settings differ")


def test_broken_asmdef_reference(pkg):
    path = pkg / "Runtime/Mocap.Imu.asmdef"
    data = json.loads(path.read_text())
    data["references"] = ["Mocap.Imu.Nope"]
    path.write_text(json.dumps(data, indent=4))
    assert problems_about(lint(pkg), "Runtime/Mocap.Imu.asmdef",
                          "reference 'Mocap.Imu.Nope' resolves to no asmdef")


def test_asmdef_reference_by_guid(pkg):
    path = pkg / "Runtime/Mocap.Imu.asmdef"
    data = json.loads(path.read_text())
    data["references"] = ["GUID:" + guid_of(pkg, "Runtime/Core/Mocap.Imu.Core.asmdef")]
    path.write_text(json.dumps(data, indent=4))
    assert lint(pkg) == []
    data["references"] = ["GUID:" + "0" * 32]
    path.write_text(json.dumps(data, indent=4))
    assert problems_about(lint(pkg), "Runtime/Mocap.Imu.asmdef", "no asmdef GUID of this package")


def test_player_assembly_must_not_reference_editor_assembly(pkg):
    path = pkg / "Runtime/Mocap.Imu.asmdef"
    data = json.loads(path.read_text())
    data["references"].append("Mocap.Imu.Editor")
    path.write_text(json.dumps(data, indent=4))
    problems = lint(pkg)
    assert problems_about(problems, "Mocap.Imu.asmdef", "references Editor-only Mocap.Imu.Editor")
    assert problems_about(problems, "asmdef", "reference cycle")


def test_duplicate_asmdef_name(pkg):
    path = pkg / "Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef"
    data = json.loads(path.read_text())
    data["name"] = "Mocap.Imu.Tests.Editor"
    path.write_text(json.dumps(data, indent=4))
    problems = lint(pkg)
    assert problems_about(problems, "Mocap.Imu.Tests.Runtime.asmdef", "is also used by")
    assert problems_about(problems, "Tests/Runtime", "'Mocap.Imu.Tests.Runtime' is missing")


@pytest.mark.parametrize("rel,key,value,message", [
    ("Tests/Editor/Core/Mocap.Imu.Core.Tests.asmdef", "defineConstraints", [], "UNITY_INCLUDE_TESTS"),
    ("Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef", "overrideReferences", False, "overrideReferences"),
    ("Tests/Editor/Mocap.Imu.Tests.Editor.asmdef", "precompiledReferences", [], "nunit.framework.dll"),
    ("Tests/Editor/Mocap.Imu.Tests.Editor.asmdef", "includePlatforms", [], "Editor test assembly"),
    ("Editor/Mocap.Imu.Editor.asmdef", "includePlatforms", [], "Editor assembly must have"),
    ("Runtime/Core/Mocap.Imu.Core.asmdef", "noEngineReferences", False, "noEngineReferences"),
])
def test_asmdef_rules(pkg, rel, key, value, message):
    path = pkg / rel
    data = json.loads(path.read_text())
    data[key] = value
    path.write_text(json.dumps(data, indent=4))
    assert problems_about(lint(pkg), rel, message)


def test_core_must_not_use_unity(pkg):
    path = pkg / "Runtime/Core/MocapEngine.cs"
    path.write_text("using UnityEngine;\n" + path.read_text())
    assert problems_about(lint(pkg), "Runtime/Core/MocapEngine.cs", "engine-free core")


def test_script_outside_every_assembly(pkg):
    (pkg / "Stray.cs").write_text("class Stray {}\n")
    unity_meta.main(["--package", str(pkg), "-q"])
    assert problems_about(lint(pkg), "Stray.cs", "outside every assembly definition")


def test_invalid_package_json(pkg):
    (pkg / "package.json").write_text('{ "name": "com.mocap.imu", ')
    problems = lint(pkg)
    assert problems_about(problems, "package.json", "invalid JSON")


def test_invalid_asmdef_json(pkg):
    (pkg / "Editor/Mocap.Imu.Editor.asmdef").write_text("{ nope")
    assert problems_about(lint(pkg), "Editor/Mocap.Imu.Editor.asmdef", "invalid JSON")


@pytest.mark.parametrize("key,value,message", [
    ("version", "0.1", "is not semver"),
    ("unity", "2022", 'is not like "2022.3"'),
    ("name", "com.mocap.other", "is not 'com.mocap.imu'"),
    ("displayName", "", '"displayName" is missing'),
    ("keywords", [], '"keywords" must be'),
    ("dependencies", {"com.github.asus4.onnxruntime": "latest"}, "is not name -> x.y.z"),
])
def test_package_json_fields(pkg, key, value, message):
    path = pkg / "package.json"
    data = json.loads(path.read_text())
    data[key] = value
    path.write_text(json.dumps(data, indent=2))
    assert problems_about(lint(pkg), "package.json", message)


def test_sample_path_must_exist(pkg):
    path = pkg / "package.json"
    data = json.loads(path.read_text())
    data["samples"] = [{"displayName": "Demo", "description": "d", "path": "Samples~/Demo"}]
    path.write_text(json.dumps(data, indent=2))
    assert problems_about(lint(pkg), "package.json", "samples[0] path 'Samples~/Demo' does not exist")
    (pkg / "Samples~/Demo").mkdir()
    assert lint(pkg) == []


def test_changelog_needs_the_version(pkg):
    path = pkg / "package.json"
    data = json.loads(path.read_text())
    data["version"] = "9.9.9"
    path.write_text(json.dumps(data, indent=2))
    assert problems_about(lint(pkg), "CHANGELOG.md", "## [9.9.9]")


def test_plugin_meta_without_platform_settings(pkg):
    rel = "Runtime/Plugins/Linux/x86_64/libmocap_imu.so"
    add_plugin(pkg, rel)
    unity_meta.main(["--package", str(pkg), "-q"])
    meta = pkg / (rel + ".meta")
    text = meta.read_text()
    head, _, _ = text.partition("  platformData:")
    meta.write_text(head + "  userData: \n  assetBundleName: \n  assetBundleVariant: \n")
    problems = lint(pkg)
    assert problems_about(problems, rel + ".meta", "no platformData")


def test_plugin_meta_with_wrong_platform(pkg):
    rel = "Runtime/Plugins/Linux/x86_64/libmocap_imu.so"
    add_plugin(pkg, rel)
    meta = pkg / (rel + ".meta")
    # A Windows importer on a Linux library (correct GUID): enables the wrong player and editor OS.
    meta.write_text(unity_meta.meta_text(rel, False, "4" * 32).split("PluginImporter:")[0]
                    + "PluginImporter:" + unity_meta.plugin_importer(".dll").split("PluginImporter:")[1])
    problems = lint(pkg)
    assert problems_about(problems, rel + ".meta", "must enable the Linux64 player")
    assert problems_about(problems, rel + ".meta", "must enable the Editor on Linux")


def test_plugin_meta_with_default_importer(pkg):
    rel = "Runtime/Plugins/Windows/x86_64/mocap_imu.dll"
    add_plugin(pkg, rel)
    (pkg / (rel + ".meta")).write_text(unity_meta.meta_text("Runtime/Plugins/Windows/x86_64/x.txt",
                                                            False, "5" * 32))
    unity_meta_missing = unity_meta.plan(pkg)[0]
    for i, m in enumerate(unity_meta_missing):  # the new folders' metas
        (pkg / m).write_text(unity_meta.meta_text(m[:-5], True, f"{i:032x}"))
    assert problems_about(lint(pkg), rel + ".meta", "no PluginImporter section")


def test_plugin_outside_its_platform_folder(pkg):
    add_plugin(pkg, "Runtime/Plugins/libmocap_imu.so")
    unity_meta.main(["--package", str(pkg), "-q"])
    assert problems_about(lint(pkg), "Runtime/Plugins/libmocap_imu.so",
                          "must live under Runtime/Plugins/Linux/")


@pytest.mark.skipif(shutil.which("git") is None, reason="git not installed")
def test_plugin_binaries_are_ignored_build_outputs(tmp_path, pkg):
    repo = tmp_path / "repo"
    (repo / "Packages").mkdir(parents=True)
    shutil.copy(REPO / ".gitignore", repo / ".gitignore")
    shutil.move(str(pkg), repo / "Packages" / "com.mocap.imu")
    p = repo / "Packages" / "com.mocap.imu"
    add_plugin(p, "Runtime/Plugins/Linux/x86_64/libmocap_imu.so")
    unity_meta.main(["--package", str(p), "-q"])
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run(git + ["init", "-q"], check=True)
    subprocess.run(git + ["add", "-A"], check=True)
    tracked = subprocess.run(git + ["ls-files"], check=True, capture_output=True, text=True).stdout
    assert "Runtime/Plugins" not in tracked and "Runtime/Core/MocapEngine.cs.meta" in tracked
    assert package_lint.lint(p, use_git=True) == []
    subprocess.run(git + ["add", "-f", "Packages/com.mocap.imu/Runtime/Plugins"], check=True)
    problems = package_lint.lint(p, use_git=True)
    assert problems_about(problems, "Runtime/Plugins/Linux/x86_64/libmocap_imu.so", "tracked by git")


def test_cli_exit_status_and_output(pkg):
    ok = subprocess.run([sys.executable, str(SCRIPTS / "package_lint.py"), "--package", str(pkg),
                         "--no-git"], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stdout
    assert "0 problem(s)" in ok.stdout
    (pkg / "Runtime/Core/Calibration.cs.meta").unlink()
    bad = subprocess.run([sys.executable, str(SCRIPTS / "package_lint.py"), "--package", str(pkg),
                          "--no-git"], capture_output=True, text=True)
    assert bad.returncode == 1
    assert f"{pkg / 'Runtime/Core/Calibration.cs'}: has no .meta file" in bad.stdout
    check = subprocess.run([sys.executable, str(SCRIPTS / "unity_meta.py"), "--package", str(pkg),
                            "--check"], capture_output=True, text=True)
    assert check.returncode == 1 and "Calibration.cs: missing .meta file" in check.stdout


# ------------------------------------------------------------------ platforms of the assemblies

NATIVE = ["Editor", "LinuxStandalone64", "macOSStandalone", "WindowsStandalone64"]


@pytest.mark.parametrize("rel", [
    "Runtime/Core/Mocap.Imu.Core.asmdef",
    "Runtime/Mocap.Imu.asmdef",
    "Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef",
])
def test_engine_assemblies_are_limited_to_the_plugin_platforms(rel):
    data = json.loads((REAL_PACKAGE / rel).read_text())
    assert set(data["includePlatforms"]) == set(NATIVE) and data["excludePlatforms"] == []


@pytest.mark.parametrize("rel", [
    "Runtime/Core/Mocap.Imu.Core.asmdef",
    "Runtime/Mocap.Imu.asmdef",
    "Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef",
])
def test_an_engine_assembly_on_every_platform_fails(pkg, rel):
    edit_json(pkg / rel, includePlatforms=[])
    problems = lint(pkg)
    assert problems_about(problems, rel, "needs the native engine but compiles for")
    assert problems_about(problems, rel, "Android")


def test_an_engine_assembly_on_a_platform_without_plugin_fails(pkg):
    rel = "Runtime/Mocap.Imu.asmdef"
    edit_json(pkg / rel, includePlatforms=NATIVE + ["Android"])
    problems = lint(pkg)
    assert problems_about(problems, rel, "compiles for Android, where no plugin is built")
    # ...and the runtime would compile on Android without the core it references.
    assert problems_about(problems, rel, "compiles for Android, where its reference Mocap.Imu.Core")


def test_excluding_platforms_instead_still_fails_for_the_rest(pkg):
    rel = "Runtime/Core/Mocap.Imu.Core.asmdef"
    edit_json(pkg / rel, includePlatforms=[], excludePlatforms=["Android", "iOS"])
    problems = lint(pkg)
    assert problems_about(problems, rel, "needs the native engine but compiles for")
    assert problems_about(problems, rel, "WSA") and not problems_about(problems, rel, "Android")


def test_a_reference_missing_on_a_platform_fails(pkg):
    # The runtime narrowed to the Editor: the PlayMode tests (every native platform) lose it.
    edit_json(pkg / "Runtime/Mocap.Imu.asmdef", includePlatforms=["Editor"])
    problems = lint(pkg)
    assert problems_about(problems, "Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef",
                          "where its reference Mocap.Imu does not")
    assert problems_about(problems, "Tests/Runtime/Mocap.Imu.Tests.Runtime.asmdef",
                          "references Editor-only Mocap.Imu")
    # ...and so do the samples' assemblies, limited to the same platforms.
    for sample in ("LiveAvatar", "CapturePlayback", "VrAvatar", "MultiCharacter"):
        rel = f"Samples~/{sample}/Mocap.Imu.Samples.{sample}.asmdef"
        assert problems_about(problems, rel, "where its reference Mocap.Imu does not")
        assert problems_about(problems, rel, "references Editor-only Mocap.Imu")
    assert len(problems) == 10, problems


@pytest.mark.parametrize("platforms,message", [
    (["Editor", "Linux64"], "'Linux64', which is no Unity platform"),
    (["Editor", "StandaloneWindows64"], "'StandaloneWindows64', which is no Unity platform"),
    ("Editor", "must be a list of platform names"),
])
def test_platform_names_are_unitys(pkg, platforms, message):
    rel = "Runtime/Core/Mocap.Imu.Core.asmdef"
    edit_json(pkg / rel, includePlatforms=platforms)
    assert problems_about(lint(pkg), rel, message)


def test_include_and_exclude_together_fail(pkg):
    rel = "Editor/Mocap.Imu.Editor.asmdef"
    edit_json(pkg / rel, excludePlatforms=["Android"])
    assert problems_about(lint(pkg), rel, "both set")


def test_a_new_assembly_calling_the_engine_is_found_by_its_dllimport(pkg):
    folder = pkg / "Runtime/Extra"
    folder.mkdir()
    (folder / "Extra.cs").write_text(
        "using System.Runtime.InteropServices;\n"
        "static class Extra { [DllImport(\"mocap_imu\")] static extern int mocap_api_version(); }\n")
    edit_json(folder / "Mocap.Imu.Extra.asmdef", name="Mocap.Imu.Extra", references=[],
              includePlatforms=[], noEngineReferences=True)
    unity_meta.main(["--package", str(pkg), "-q"])
    assert problems_about(lint(pkg), "Runtime/Extra/Mocap.Imu.Extra.asmdef",
                          "needs the native engine")
    edit_json(folder / "Mocap.Imu.Extra.asmdef", includePlatforms=NATIVE)
    assert lint(pkg) == []


# ------------------------------------------------------------------------- built-in modules

def dependencies(pkg, **changes):
    path = pkg / "package.json"
    data = json.loads(path.read_text())
    for name, version in changes.items():
        name = name.replace("__", ".").replace("_", "-")
        if version is None:
            del data["dependencies"][name]
        else:
            data["dependencies"][name] = version
    path.write_text(json.dumps(data, indent=2))


def test_the_real_package_declares_the_modules_it_uses():
    deps = json.loads((REAL_PACKAGE / "package.json").read_text())["dependencies"]
    for module in ("physics", "animation", "imgui", "vr"):
        assert deps[f"com.unity.modules.{module}"] == "1.0.0"
    assert "com.unity.test-framework" in deps


@pytest.mark.parametrize("module", ["physics", "animation", "imgui", "vr"])
def test_a_used_module_missing_from_the_dependencies_fails(pkg, module):
    dependencies(pkg, **{f"com__unity__modules__{module}": None})
    problems = lint(pkg)
    assert problems_about(problems, "package.json", f"com.unity.modules.{module}")
    assert len(problems) == 1, problems
    # The problem names a file of the package that uses the module (the first one found).
    named = re.search(r"package\.json: (\S+\.cs) uses", problems[0])
    assert named, problems[0]
    assert (pkg / named.group(1)).is_file(), problems[0]


def test_a_declared_module_nothing_uses_fails(pkg):
    dependencies(pkg, com__unity__modules__jsonserialize="1.0.0")
    assert problems_about(lint(pkg), "package.json",
                          "declares com.unity.modules.jsonserialize, which no script")


def test_a_module_version_other_than_1_0_0_fails(pkg):
    dependencies(pkg, com__unity__modules__physics="2.0.0")
    assert problems_about(lint(pkg), "package.json", 'com.unity.modules.physics must be "1.0.0"')


def test_comments_and_strings_are_not_uses_but_code_is(pkg):
    path = pkg / "Runtime/HumanoidPoseDriver.cs"
    text = path.read_text()
    path.write_text(text + '\n// JsonUtility would do\n/* InputDevices */\n'
                    'static class Names { const string A = "JsonUtility"; const string B = @"XRSettings"; }\n')
    assert lint(pkg) == []
    path.write_text(text + "\nstatic class Uses { static string S(object o) => "
                    "UnityEngine.JsonUtility.ToJson(o); }\n")
    assert problems_about(lint(pkg), "package.json",
                          "Runtime/HumanoidPoseDriver.cs uses JsonUtility (built-in module "
                          "com.unity.modules.jsonserialize)")


def test_the_engine_free_core_is_not_scanned(pkg):
    # The core's own names (its Avatar-free HumanBone, a "Physics" word) are not Unity's.
    path = pkg / "Runtime/Core/MocapEngine.cs"
    path.write_text(path.read_text() + "\nnamespace Mocap.Imu { static class Physics { } }\n")
    dependencies(pkg, com__unity__modules__physics=None)
    problems = lint(pkg)
    assert [p for p in problems if "MocapEngine.cs" in p] == []


def test_test_assemblies_need_the_test_framework(pkg):
    dependencies(pkg, com__unity__test_framework=None)
    assert problems_about(lint(pkg), "package.json", "needs com.unity.test-framework")


# ------------------------------------------------------------------------------ samples' asmdefs

SAMPLES = ("LiveAvatar", "CapturePlayback", "VrAvatar", "MultiCharacter")


def sample_asmdef(sample):
    return f"Samples~/{sample}/Mocap.Imu.Samples.{sample}.asmdef"


@pytest.mark.parametrize("sample", SAMPLES)
def test_each_real_sample_is_an_assembly_limited_to_the_plugin_platforms(sample):
    # Imported, a sample outside an asmdef would be Assembly-CSharp on every platform, where the
    # package's assemblies it uses do not exist (an Android or iOS player build would not compile).
    data = json.loads((REAL_PACKAGE / sample_asmdef(sample)).read_text())
    assert data["name"] == f"Mocap.Imu.Samples.{sample}"
    assert set(data["includePlatforms"]) == set(NATIVE) and data["excludePlatforms"] == []
    assert set(data["references"]) == {"Mocap.Imu", "Mocap.Imu.Core"}
    assert sorted(p.name for p in (REAL_PACKAGE / "Samples~" / sample).glob("*.asmdef")) == \
        [f"Mocap.Imu.Samples.{sample}.asmdef"]


def test_a_sample_asmdef_on_every_platform_fails(pkg):
    rel = sample_asmdef("VrAvatar")
    edit_json(pkg / rel, includePlatforms=[])
    problems = lint(pkg)
    engine_problems = problems_about(problems, rel, "needs the native engine")
    assert all(p in engine_problems[0] for p in ("Android", "iOS", "WebGL")), engine_problems
    assert problems_about(problems, rel, "where its reference Mocap.Imu does not")
    assert all(rel in p for p in problems), problems


def test_a_sample_asmdef_adding_a_platform_without_plugin_fails(pkg):
    rel = sample_asmdef("LiveAvatar")
    edit_json(pkg / rel, includePlatforms=NATIVE + ["Android"])
    problems = lint(pkg)
    assert problems_about(problems, rel, "compiles for Android, where no plugin is built")
    assert problems_about(problems, rel, "compiles for Android, where its reference Mocap.Imu.Core")


def test_a_sample_without_asmdef_using_the_package_fails(pkg):
    (pkg / sample_asmdef("CapturePlayback")).unlink()
    problems = lint(pkg)
    assert problems_about(problems, "Samples~/CapturePlayback/CapturePlaybackBootstrap.cs",
                          "uses Mocap.Imu outside an asmdef of its sample")
    assert len(problems) == 1, problems
    # Code that does not name the package, and editor scripts (Assembly-CSharp-Editor exists in
    # the editor only), may stay outside an asmdef.
    (pkg / "Samples~/CapturePlayback/CapturePlaybackBootstrap.cs").write_text(
        "// Mocap.Imu is named in a comment only\n"
        "public sealed class Plain : UnityEngine.MonoBehaviour { string s = \"Mocap.Imu\"; }\n")
    (pkg / "Samples~/CapturePlayback/Editor").mkdir()
    (pkg / "Samples~/CapturePlayback/Editor/Menu.cs").write_text(
        "using Mocap.Imu;\nstatic class Menu { }\n")
    assert lint(pkg) == []


def test_a_sample_asmdef_in_an_editor_folder_must_be_editor_only(pkg):
    folder = pkg / "Samples~/VrAvatar/Editor"
    folder.mkdir()
    rel = "Samples~/VrAvatar/Editor/Mocap.Imu.Samples.VrAvatar.Editor.asmdef"
    edit_json(pkg / rel, name="Mocap.Imu.Samples.VrAvatar.Editor",
              references=["Mocap.Imu.Samples.VrAvatar", "Mocap.Imu.Editor"], includePlatforms=NATIVE)
    problems = lint(pkg)
    assert problems_about(problems, rel, 'Editor assembly must have includePlatforms ["Editor"]')
    assert problems_about(problems, rel, "references Editor-only Mocap.Imu.Editor")
    edit_json(pkg / rel, includePlatforms=["Editor"])
    assert lint(pkg) == []


def test_a_sample_asmdef_references_the_package_or_its_own_sample_only(pkg):
    rel = sample_asmdef("MultiCharacter")
    mocap_imu_guid = guid_of(pkg, "Runtime/Mocap.Imu.asmdef")
    edit_json(pkg / rel, references=["Mocap.Imu.Core", "GUID:" + mocap_imu_guid])
    assert lint(pkg) == []
    edit_json(pkg / rel, references=["Mocap.Imu.Core", "Mocap.Imu", "Mocap.Imu.Samples.LiveAvatar"])
    assert problems_about(lint(pkg), rel, "is an asmdef of Samples~/LiveAvatar: a project may "
                          "have imported this sample alone")
    edit_json(pkg / rel, references=["Mocap.Imu.Core", "Mocap.Imu", "Mocap.Imu.Nope"])
    assert problems_about(lint(pkg), rel, "'Mocap.Imu.Nope' resolves to no asmdef")


@pytest.mark.parametrize("name", ["Mocap.Imu.Samples.LiveAvatar", "Mocap.Imu"])
def test_a_sample_asmdef_name_must_be_unique(pkg, name):
    rel = sample_asmdef("VrAvatar")
    edit_json(pkg / rel, name=name)
    assert problems_about(lint(pkg), rel, f"asmdef name {name!r} is also used by")
