"""Tests of the Unity compile gate (dotnet/Mocap.Imu.CompileGate).

The gate must pass the real package and fail, naming the unit, the file and the compiler's
diagnostic, on copies broken in the ways the Unity layer broke before: a type error in one
sample, a sample using another sample's class, an API obsolete in Unity 6 only, editor API in a
runtime assembly, an inspector field without a tooltip, and a sample that would be compiled
for a platform (Android) where the package's assemblies are left out."""

import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent.parent
REAL_PACKAGE = REPO / "Packages" / "com.mocap.imu"
GATE_PROJECT = REPO / "dotnet" / "Mocap.Imu.CompileGate"
UNIT_LINE = re.compile(r"^compile unit (.+) \[unity-(\S+) (\S+)\]: (ok|FAILED)$")
NOT_BUILT_LINE = re.compile(r"^not built for \[unity-(\S+) (\S+)\] \(platforms or defineConstraints\): (.+)$")
SUMMARY = re.compile(r"^(\d+) compile units ok, (\d+) failed$")
VERSIONS = ("2022.3", "6000.0")
PLAYERS = ("player-windows", "player-linux", "player-macos")
# The package's assemblies need the native plugin, so they leave this player out.
NO_PLUGIN_PLAYER = "player-android"
SAMPLES = ("LiveAvatar", "CapturePlayback", "VrAvatar", "MultiCharacter")


@pytest.fixture(scope="module")
def gate_dll(tmp_path_factory):
    """The gate, built once (a missing SDK fails the suite: a skip would pass nothing)."""
    if shutil.which("dotnet") is None:
        pytest.fail("the .NET SDK (dotnet) is not installed: the compile gate cannot run")
    out = tmp_path_factory.mktemp("gate-build")
    build = subprocess.run(["dotnet", "build", str(GATE_PROJECT), "-v", "q", "-o", str(out)],
                           capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stdout + build.stderr
    dll = out / "Mocap.Imu.CompileGate.dll"
    assert dll.is_file()
    return dll


NOT_BUILT = {}  # (package folder, version, target) -> assemblies the gate said it left out


def run_gate(dll, package):
    """Runs the gate; returns (exit code, {(unit, version, target): [diagnostics]}, ok, failed).
    The assemblies it reports as not built are kept in NOT_BUILT (see not_built)."""
    proc = subprocess.run(["dotnet", str(dll), str(package)], capture_output=True, text=True, timeout=900)
    units, current = {}, None
    summary = None
    for line in proc.stdout.splitlines():
        m = UNIT_LINE.match(line)
        if m:
            current = (m.group(1), m.group(2), m.group(3))
            assert current not in units, f"unit reported twice: {line}"
            units[current] = [] if m.group(4) == "ok" else ["FAILED"]
        elif line.startswith("  ") and current is not None:
            units[current].append(line.strip())
        elif NOT_BUILT_LINE.match(line):
            m = NOT_BUILT_LINE.match(line)
            NOT_BUILT[(str(package), m.group(1), m.group(2))] = set(m.group(3).split(", "))
            current = None
        elif SUMMARY.match(line):
            summary = SUMMARY.match(line)
    assert summary is not None, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert proc.stdout.rstrip().splitlines()[-1] == summary.group(0), "the summary must be the last line"
    return proc.returncode, units, int(summary.group(1)), int(summary.group(2))


def not_built(package, version, target):
    return NOT_BUILT.get((str(package), version, target), set())


def failed(units, key):
    return units[key] and units[key][0] == "FAILED"


def edit_asmdef(path, **changes):
    data = json.loads(path.read_text()) if path.exists() else {}
    data.update(changes)
    path.write_text(json.dumps(data, indent=4))


def copy_package(tmp_path):
    dest = tmp_path / "com.mocap.imu"
    shutil.copytree(REAL_PACKAGE, dest, ignore=shutil.ignore_patterns(
        "Native~", "Plugins", "*.onnx", "*.cap", "__pycache__", "bin", "obj"))
    return dest


def test_the_real_package_compiles_in_every_unit(gate_dll):
    code, units, ok, bad = run_gate(gate_dll, REAL_PACKAGE)
    problems = {k: v for k, v in units.items() if failed(units, k)}
    assert code == 0 and bad == 0, problems
    assert ok == len(units) > 0
    for version in VERSIONS:
        # Every asmdef in the editor; the runtime assemblies (no editor, no tests) in every player.
        for asmdef in ("Mocap.Imu.Core", "Mocap.Imu", "Mocap.Imu.Editor", "Mocap.Imu.Core.Tests",
                       "Mocap.Imu.Tests.Editor", "Mocap.Imu.Tests.Runtime"):
            assert (asmdef, version, "editor") in units
        for player in PLAYERS:
            assert ("Mocap.Imu", version, player) in units
            assert ("Mocap.Imu.Editor", version, player) not in units
            assert ("Mocap.Imu.Tests.Runtime", version, player) not in units  # UNITY_INCLUDE_TESTS
        # Each sample alone, as its own assembly (all its scripts are in it: no Assembly-CSharp).
        for sample in SAMPLES:
            for target in ("editor",) + PLAYERS:
                assert (f"Samples~/{sample} Mocap.Imu.Samples.{sample}", version, target) in units
                assert (f"Samples~/{sample} Assembly-CSharp", version, target) not in units
        # Android: no plugin, so neither the package nor the samples build there, and say so.
        assert not [k for k in units if k[2] == NO_PLUGIN_PLAYER], units
        left_out = not_built(REAL_PACKAGE, version, NO_PLUGIN_PLAYER)
        assert {"Mocap.Imu.Core", "Mocap.Imu", "Mocap.Imu.Editor"} <= left_out, left_out
        assert {f"Samples~/{s} Mocap.Imu.Samples.{s}" for s in SAMPLES} <= left_out, left_out
        for player in PLAYERS:
            assert not any(s.startswith("Samples~/") for s in not_built(REAL_PACKAGE, version, player))


def test_broken_copies_fail_in_the_right_units_only(gate_dll, tmp_path):
    pkg = copy_package(tmp_path)
    # A type error in one sample.
    with open(pkg / "Samples~/CapturePlayback/CapturePlaybackBootstrap.cs", "a") as f:
        f.write("\nstatic class BrokenOnPurpose { static int Count() => \"not a number\"; }\n")
    # A sample that leans on another sample's class (only compiles with both imported), even
    # naming the other sample's assembly: a project that imported this sample alone lacks it.
    with open(pkg / "Samples~/MultiCharacter/MultiCharacterBootstrap.cs", "a") as f:
        f.write("\nstatic class BorrowsFromAnotherSample { static System.Type T => typeof(LiveAvatarBootstrap); }\n")
    edit_asmdef(pkg / "Samples~/MultiCharacter/Mocap.Imu.Samples.MultiCharacter.asmdef",
                references=["Mocap.Imu.Core", "Mocap.Imu", "Mocap.Imu.Samples.LiveAvatar"])
    # An API that Unity 6 made obsolete (fine in 2022.3), in the runtime assembly.
    (pkg / "Runtime/ObsoleteInUnity6.cs").write_text(
        "namespace Mocap.Imu { static class ObsoleteInUnity6 {\n"
        "    public static UnityEngine.Light AnyLight() => UnityEngine.Object.FindObjectOfType<UnityEngine.Light>(); } }\n")
    # Editor API in the runtime assembly without #if UNITY_EDITOR: fine in the editor, not in a player.
    (pkg / "Runtime/EditorApiInRuntime.cs").write_text(
        "namespace Mocap.Imu { static class EditorApiInRuntime {\n"
        "    public static bool Playing => UnityEditor.EditorApplication.isPlaying; } }\n")
    # UnityEngine in the engine-free core, whose asmdef says noEngineReferences.
    (pkg / "Runtime/Core/UsesTheEngine.cs").write_text(
        "namespace Mocap.Imu { static class UsesTheEngine { public static UnityEngine.Vector3 Up => UnityEngine.Vector3.up; } }\n")
    # A sample's editor script with the sample's editor asmdef (Editor-only, referencing the
    # sample's assembly): compiled in the editor only.
    (pkg / "Samples~/VrAvatar/Editor").mkdir()
    edit_asmdef(pkg / "Samples~/VrAvatar/Editor/Mocap.Imu.Samples.VrAvatar.Editor.asmdef",
                name="Mocap.Imu.Samples.VrAvatar.Editor", references=["Mocap.Imu.Samples.VrAvatar"],
                includePlatforms=["Editor"])
    (pkg / "Samples~/VrAvatar/Editor/VrAvatarMenu.cs").write_text(
        "static class VrAvatarMenu {\n"
        "    [UnityEditor.MenuItem(\"Tools/Select VR bootstrap\")]\n"
        "    static void Select() => UnityEditor.Selection.activeObject =\n"
        "        UnityEngine.Object.FindAnyObjectByType<VrAvatarBootstrap>(); }\n")
    # An inspector field without a tooltip.
    (pkg / "Runtime/Untipped.cs").write_text(
        "namespace Mocap.Imu { public sealed class Untipped : UnityEngine.MonoBehaviour {\n"
        "    [UnityEngine.Tooltip(\"Documented.\")] public float documented;\n"
        "    public float speed; } }\n")

    code, units, ok, bad = run_gate(gate_dll, pkg)
    assert code == 1 and bad > 0 and ok > 0

    for version in VERSIONS:
        for target in ("editor",) + PLAYERS:
            playback = units[("Samples~/CapturePlayback Mocap.Imu.Samples.CapturePlayback", version, target)]
            assert any("CapturePlaybackBootstrap.cs:" in d and "CS0029" in d for d in playback), playback
            multi = units[("Samples~/MultiCharacter Mocap.Imu.Samples.MultiCharacter", version, target)]
            assert any("MultiCharacterBootstrap.cs:" in d and "CS0246" in d and "LiveAvatarBootstrap" in d
                       for d in multi), multi
            assert any("Mocap.Imu.Samples.MultiCharacter.asmdef: reference 'Mocap.Imu.Samples.LiveAvatar' "
                       "is neither an asmdef it can see" in d for d in multi), multi
            # The other samples compile alone, untouched by their neighbours' errors.
            assert units[("Samples~/LiveAvatar Mocap.Imu.Samples.LiveAvatar", version, target)] == []
            assert units[("Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar", version, target)] == []

            runtime = units[("Mocap.Imu", version, target)]
            obsolete = [d for d in runtime if "Runtime/ObsoleteInUnity6.cs:" in d and "CS0618" in d]
            assert bool(obsolete) == (version == "6000.0"), runtime
            editor_api = [d for d in runtime if "Runtime/EditorApiInRuntime.cs:" in d]
            assert bool(editor_api) == (target != "editor"), runtime

        assert units[("Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar.Editor", version, "editor")] == []
        for player in PLAYERS + (NO_PLUGIN_PLAYER,):
            assert ("Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar.Editor", version, player) not in units
            assert "Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar.Editor" in not_built(pkg, version, player)

        editor_runtime = units[("Mocap.Imu", version, "editor")]
        assert any("Runtime/Untipped.cs:3: inspector field 'speed' of Untipped has no [Tooltip]" in d
                   for d in editor_runtime), editor_runtime
        assert not any("'documented'" in d for d in editor_runtime)
        for target in ("editor",) + PLAYERS:
            core = units[("Mocap.Imu.Core", version, target)]
            assert any("Runtime/Core/UsesTheEngine.cs:" in d and "UnityEngine" in d for d in core), core
        # An assembly that references broken ones without using what broke still compiles.
        assert units[("Mocap.Imu.Tests.Editor", version, "editor")] == []


def test_a_sample_builds_where_its_asmdef_says_and_only_there(gate_dll, tmp_path):
    """An imported sample without an asmdef is Assembly-CSharp on every platform: on Android,
    where the package's assemblies are left out, it cannot compile. Its asmdef limited to the
    package's platforms fixes that; one that names every platform does not."""
    pkg = copy_package(tmp_path)
    live = pkg / "Samples~/LiveAvatar/Mocap.Imu.Samples.LiveAvatar.asmdef"
    live_asmdef = live.read_text()
    live.unlink()
    # Outside every asmdef an Editor/ folder is Assembly-CSharp-Editor: editor only, and it
    # sees the sample's runtime scripts.
    (pkg / "Samples~/LiveAvatar/Editor").mkdir()
    (pkg / "Samples~/LiveAvatar/Editor/LiveAvatarMenu.cs").write_text(
        "static class LiveAvatarMenu {\n"
        "    [UnityEditor.MenuItem(\"Tools/Select live bootstrap\")]\n"
        "    static void Select() => UnityEditor.Selection.activeObject =\n"
        "        UnityEngine.Object.FindAnyObjectByType<LiveAvatarBootstrap>(); }\n")
    playback = pkg / "Samples~/CapturePlayback/Mocap.Imu.Samples.CapturePlayback.asmdef"
    edit_asmdef(playback, includePlatforms=[])
    # Inside an asmdef an Editor/ folder is nothing special: its script is part of the sample's
    # player assembly, which has no UnityEditor.
    (pkg / "Samples~/MultiCharacter/Editor").mkdir()
    (pkg / "Samples~/MultiCharacter/Editor/MultiCharacterMenu.cs").write_text(
        "static class MultiCharacterMenu {\n"
        "    [UnityEditor.MenuItem(\"Tools/Mocap sample\")] static void Open() { } }\n")

    code, units, ok, bad = run_gate(gate_dll, pkg)
    assert code == 1 and bad > 0
    for version in VERSIONS:
        live_unit = ("Samples~/LiveAvatar Assembly-CSharp", version, NO_PLUGIN_PLAYER)
        assert any("LiveAvatarBootstrap.cs:1: error CS0246" in d and "'Mocap'" in d
                   for d in units[live_unit]), units[live_unit]
        playback_unit = ("Samples~/CapturePlayback Mocap.Imu.Samples.CapturePlayback", version, NO_PLUGIN_PLAYER)
        assert any("CapturePlaybackBootstrap.cs:1: error CS0246" in d for d in units[playback_unit]), \
            units[playback_unit]
        for target in ("editor",) + PLAYERS:
            assert units[("Samples~/LiveAvatar Assembly-CSharp", version, target)] == []
            assert units[("Samples~/CapturePlayback Mocap.Imu.Samples.CapturePlayback", version, target)] == []
            multi = units[("Samples~/MultiCharacter Mocap.Imu.Samples.MultiCharacter", version, target)]
            menu_errors = [d for d in multi if "Editor/MultiCharacterMenu.cs:" in d]
            assert bool(menu_errors) == (target != "editor"), multi
        assert units[("Samples~/LiveAvatar Assembly-CSharp-Editor", version, "editor")] == []
        assert ("Samples~/LiveAvatar Assembly-CSharp-Editor", version, NO_PLUGIN_PLAYER) not in units
        # The untouched sample is left out of Android, as its asmdef says.
        assert ("Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar", version, NO_PLUGIN_PLAYER) not in units
        assert "Samples~/VrAvatar Mocap.Imu.Samples.VrAvatar" in not_built(pkg, version, NO_PLUGIN_PLAYER)
    failed_units = {k for k in units if failed(units, k)}
    assert all(k[0].startswith(("Samples~/LiveAvatar", "Samples~/CapturePlayback", "Samples~/MultiCharacter"))
               for k in failed_units), failed_units

    # The same samples with their asmdefs limited to the package's platforms: every unit passes.
    live.write_text(live_asmdef)
    shutil.rmtree(pkg / "Samples~/LiveAvatar/Editor")
    shutil.rmtree(pkg / "Samples~/MultiCharacter/Editor")
    edit_asmdef(playback, includePlatforms=json.loads(live_asmdef)["includePlatforms"])
    code, units, ok, bad = run_gate(gate_dll, pkg)
    assert (code, bad) == (0, 0), {k: v for k, v in units.items() if failed(units, k)}
    assert not [k for k in units if k[2] == NO_PLUGIN_PLAYER]


def test_sample_asmdef_names_must_not_clash(gate_dll, tmp_path):
    # A user may import every sample: two assemblies of one name would not compile there.
    pkg = copy_package(tmp_path)
    edit_asmdef(pkg / "Samples~/VrAvatar/Mocap.Imu.Samples.VrAvatar.asmdef", name="Mocap.Imu.Samples.LiveAvatar")
    code, units, ok, bad = run_gate(gate_dll, pkg)
    assert (code, ok, bad) == (1, 0, 1) and units == {}
    proc = subprocess.run(["dotnet", str(gate_dll), str(pkg)], capture_output=True, text=True, timeout=120)
    assert "error: two asmdefs are named Mocap.Imu.Samples.LiveAvatar (Samples~/LiveAvatar/" in proc.stdout


def test_bad_arguments_are_refused_with_a_reason(gate_dll, tmp_path):
    proc = subprocess.run(["dotnet", str(gate_dll), str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "holds no package.json" in proc.stderr
