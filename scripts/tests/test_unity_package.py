"""Tests of scripts/unity_meta.py (deterministic .meta generation) and scripts/package_lint.py.

The linter must pass on the real package and fail, naming the file, on damaged copies."""

import hashlib
import json
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


def add_plugin(pkg, rel, content=b"\x7fELF fake"):
    path = pkg / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(content)
    return path


# ------------------------------------------------------------------------------ the generator

def test_guid_is_sha256_of_package_and_path():
    want = hashlib.sha256(b"com.mocap.imu/Runtime/Core/MocapEngine.cs").hexdigest()[:32]
    assert unity_meta.guid_for("Runtime/Core/MocapEngine.cs") == want
    assert unity_meta.guid_for("Runtime") != unity_meta.guid_for("Runtime/")
    assert len(set(unity_meta.guid_for(f"a/{i}") for i in range(1000))) == 1000


def test_committed_metas_match_the_generator():
    missing, stale, orphans = unity_meta.plan(REAL_PACKAGE)
    assert (missing, stale, orphans) == ([], [], []), \
        "run `python3 scripts/unity_meta.py` (missing/stale/orphan .meta files)"


def test_generator_is_deterministic_across_locations(tmp_path, pkg):
    other = tmp_path / "elsewhere" / "com.mocap.imu"
    shutil.copytree(pkg, other, copy_function=_copy_fn)
    for root in (pkg, other):
        for m in root.rglob("*.meta"):
            m.unlink()
        assert unity_meta.main(["--package", str(root), "-q"]) == 0
    first, second = meta_files(pkg), meta_files(other)
    assert first and first == second
    # ...and identical to the committed ones.
    committed = {k: v for k, v in meta_files(REAL_PACKAGE).items()
                 if not k.startswith("Runtime/Plugins") and not k.startswith("Native~")}
    assert len(committed) > 50
    assert {k: first.get(k) for k in committed} == committed


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
    text = unity_meta.meta_text(rel, is_dir)
    assert text.startswith(f"fileFormatVersion: 2\nguid: {unity_meta.guid_for(rel)}\n")
    assert needle in text
    assert ("folderAsset: yes" in text) == is_dir


@pytest.mark.parametrize("rel,editor_os,player", [
    ("Runtime/Plugins/Linux/x86_64/libmocap_imu.so", "Linux", "Linux64"),
    ("Runtime/Plugins/Windows/x86_64/mocap_imu.dll", "Windows", "Win64"),
    ("Runtime/Plugins/macOS/libmocap_imu.dylib", "OSX", "OSXUniversal"),
    ("Runtime/Plugins/macOS/mocap_imu.bundle", "OSX", "OSXUniversal"),
])
def test_plugin_meta_enables_its_platform_only(rel, editor_os, player):
    tree = package_lint.parse_meta(unity_meta.meta_text(rel, False))
    pdata = tree["PluginImporter"]["platformData"]
    enabled = {k for k, v in pdata.items() if v.get("enabled") == "1"}
    assert enabled == {"Editor", player}
    assert pdata["Editor"]["settings"]["OS"] == editor_os
    assert pdata["Any"]["settings"][f"Exclude {player}"] == "0"


def test_generator_removes_orphans_and_check_lists_them(pkg, capsys):
    orphan = pkg / "Runtime" / "Gone.cs.meta"
    orphan.write_text(unity_meta.meta_text("Runtime/Gone.cs", False))
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
    (pkg / "Runtime/Deleted.cs.meta").write_text(unity_meta.meta_text("Runtime/Deleted.cs", False))
    assert problems_about(lint(pkg), "Runtime/Deleted.cs.meta", "orphan .meta")


def test_orphan_plugin_meta_without_binary(pkg):
    so = add_plugin(pkg, "Runtime/Plugins/Linux/x86_64/libmocap_imu.so")
    unity_meta.main(["--package", str(pkg), "-q"])
    so.unlink()
    assert problems_about(lint(pkg), "libmocap_imu.so.meta", "orphan .meta")


def test_duplicated_guid(pkg):
    a = pkg / "Runtime/Core/MocapEngine.cs.meta"
    b = pkg / "Runtime/Core/MocapSession.cs.meta"
    guid_a = unity_meta.guid_for("Runtime/Core/MocapEngine.cs")
    b.write_text(b.read_text().replace(unity_meta.guid_for("Runtime/Core/MocapSession.cs"), guid_a))
    problems = lint(pkg)
    dup = [p for p in problems if "duplicate GUID " + guid_a in p]
    assert len(dup) == 1 and "MocapEngine.cs.meta" in dup[0] and "MocapSession.cs.meta" in dup[0]
    assert problems_about(problems, "MocapSession.cs.meta", "is not the path-derived")
    assert a.exists()


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
    data["references"] = ["GUID:" + unity_meta.guid_for("Runtime/Core/Mocap.Imu.Core.asmdef")]
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
    ("name", "com.mocap.other", "GUIDs are derived from it"),
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
    meta.write_text(unity_meta.meta_text(rel, False).split("PluginImporter:")[0]
                    + "PluginImporter:" + unity_meta.plugin_importer(".dll").split("PluginImporter:")[1])
    problems = lint(pkg)
    assert problems_about(problems, rel + ".meta", "must enable the Linux64 player")
    assert problems_about(problems, rel + ".meta", "must enable the Editor on Linux")


def test_plugin_meta_with_default_importer(pkg):
    rel = "Runtime/Plugins/Windows/x86_64/mocap_imu.dll"
    add_plugin(pkg, rel)
    (pkg / (rel + ".meta")).write_text(unity_meta.meta_text("Runtime/Plugins/Windows/x86_64/x.txt",
                                                            False).replace(
        unity_meta.guid_for("Runtime/Plugins/Windows/x86_64/x.txt"), unity_meta.guid_for(rel)))
    unity_meta_missing = unity_meta.plan(pkg)[0]
    for m in unity_meta_missing:  # the new folders' metas
        (pkg / m).write_text(unity_meta.meta_text(m[:-5], True))
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
