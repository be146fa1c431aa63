"""Tests of the Unity compile gate (dotnet/Mocap.Imu.CompileGate).

The gate must pass the real package and fail, naming the unit, the file and the compiler's
diagnostic, on copies broken in the ways the Unity layer broke before: a type error in one
sample, a sample using another sample's class, an API obsolete in Unity 6 only, editor API in a
runtime assembly, and an inspector field without a tooltip."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent.parent
REAL_PACKAGE = REPO / "Packages" / "com.mocap.imu"
GATE_PROJECT = REPO / "dotnet" / "Mocap.Imu.CompileGate"
UNIT_LINE = re.compile(r"^compile unit (.+) \[unity-(\S+) (\S+)\]: (ok|FAILED)$")
SUMMARY = re.compile(r"^(\d+) compile units ok, (\d+) failed$")
VERSIONS = ("2022.3", "6000.0")
PLAYERS = ("player-windows", "player-linux", "player-macos")


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


def run_gate(dll, package):
    """Runs the gate; returns (exit code, {(unit, version, target): [diagnostics]}, ok, failed)."""
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
        elif SUMMARY.match(line):
            summary = SUMMARY.match(line)
    assert summary is not None, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert proc.stdout.rstrip().splitlines()[-1] == summary.group(0), "the summary must be the last line"
    return proc.returncode, units, int(summary.group(1)), int(summary.group(2))


def failed(units, key):
    return units[key] and units[key][0] == "FAILED"


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
        for sample in ("LiveAvatar", "CapturePlayback", "VrAvatar", "MultiCharacter"):
            for target in ("editor",) + PLAYERS:
                assert (f"Samples~/{sample} Assembly-CSharp", version, target) in units


def test_broken_copies_fail_in_the_right_units_only(gate_dll, tmp_path):
    pkg = copy_package(tmp_path)
    # A type error in one sample.
    with open(pkg / "Samples~/CapturePlayback/CapturePlaybackBootstrap.cs", "a") as f:
        f.write("\nstatic class BrokenOnPurpose { static int Count() => \"not a number\"; }\n")
    # A sample that leans on another sample's class (only compiles with both imported).
    with open(pkg / "Samples~/MultiCharacter/MultiCharacterBootstrap.cs", "a") as f:
        f.write("\nstatic class BorrowsFromAnotherSample { static System.Type T => typeof(LiveAvatarBootstrap); }\n")
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
    # A sample's editor script (Editor/ folder): Assembly-CSharp-Editor, which sees the sample's
    # runtime scripts and UnityEditor, and exists in the editor only.
    (pkg / "Samples~/VrAvatar/Editor").mkdir()
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
            playback = units[("Samples~/CapturePlayback Assembly-CSharp", version, target)]
            assert any("CapturePlaybackBootstrap.cs:" in d and "CS0029" in d for d in playback), playback
            multi = units[("Samples~/MultiCharacter Assembly-CSharp", version, target)]
            assert any("MultiCharacterBootstrap.cs:" in d and "CS0246" in d and "LiveAvatarBootstrap" in d
                       for d in multi), multi
            # The other samples compile alone, untouched by their neighbours' errors.
            assert units[("Samples~/LiveAvatar Assembly-CSharp", version, target)] == []
            assert units[("Samples~/VrAvatar Assembly-CSharp", version, target)] == []

            runtime = units[("Mocap.Imu", version, target)]
            obsolete = [d for d in runtime if "Runtime/ObsoleteInUnity6.cs:" in d and "CS0618" in d]
            assert bool(obsolete) == (version == "6000.0"), runtime
            editor_api = [d for d in runtime if "Runtime/EditorApiInRuntime.cs:" in d]
            assert bool(editor_api) == (target != "editor"), runtime

        assert units[("Samples~/VrAvatar Assembly-CSharp-Editor", version, "editor")] == []
        for player in PLAYERS:
            assert ("Samples~/VrAvatar Assembly-CSharp-Editor", version, player) not in units

        editor_runtime = units[("Mocap.Imu", version, "editor")]
        assert any("Runtime/Untipped.cs:3: inspector field 'speed' of Untipped has no [Tooltip]" in d
                   for d in editor_runtime), editor_runtime
        assert not any("'documented'" in d for d in editor_runtime)
        for target in ("editor",) + PLAYERS:
            core = units[("Mocap.Imu.Core", version, target)]
            assert any("Runtime/Core/UsesTheEngine.cs:" in d and "UnityEngine" in d for d in core), core
        # An assembly that references broken ones without using what broke still compiles.
        assert units[("Mocap.Imu.Tests.Editor", version, "editor")] == []


def test_bad_arguments_are_refused_with_a_reason(gate_dll, tmp_path):
    proc = subprocess.run(["dotnet", str(gate_dll), str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "holds no package.json" in proc.stderr
