#!/usr/bin/env python3
"""Lints the com.mocap.imu Unity package without Unity.

Checks (each problem is printed as "<file>: <problem>"; exit status 1 when there is any):
  package.json   valid JSON; name/version/displayName/description/unity/keywords/author present
                 and well-formed; dependencies map names to versions; every sample has a
                 displayName, a description and a path "Samples~/..." that exists
  layout         README.md, CHANGELOG.md (with an entry for the package version), LICENSE.md,
                 Third Party Notices.md, Runtime/, Editor/, Tests/Editor/, Tests/Runtime/
  JSON           every .json/.asmdef/.asmref outside Native~ parses
  .meta          every file and folder outside ~ folders has one; no orphan .meta; the importer
                 section is what scripts/unity_meta.py generates; GUIDs are 32 lower-case hex
                 digits and unique across the package (never compared with the path: a GUID
                 survives a move or a rename, as users' scenes reference scripts by it)
  asmdefs        names unique; the issue's five assemblies exist; references (by name or
                 "GUID:") resolve to an asmdef of the package or a known Unity assembly; no
                 reference cycle; a player assembly never references an Editor-only one; the
                 Core has noEngineReferences and no "using UnityEngine/UnityEditor"; Editor
                 assemblies are Editor-only; test assemblies have defineConstraints
                 UNITY_INCLUDE_TESTS, overrideReferences + nunit.framework.dll, both TestRunner
                 references, autoReferenced false, and Editor-only platform under Tests/Editor;
                 every .cs belongs to an asmdef; includePlatforms/excludePlatforms hold Unity's
                 platform names, not both; an assembly that calls the native engine (DllImport)
                 or references one that does is limited to the Editor and the standalone
                 platforms a native plugin is built for; no assembly compiles on a platform
                 where one of its package references does not
  samples        a sample is copied into the user's Assets/ and compiled for every platform the
                 project builds: its asmdefs have names unique across the package and every
                 sample, references resolving to the package's asmdefs, its own or a known Unity
                 assembly (never another sample's: a user may import one alone), and the
                 package's platform rules above (engine users limited to the plugin platforms,
                 no platform a reference lacks, Editor/ asmdefs Editor-only); a sample script
                 outside its sample's asmdefs and Editor/ folders must not use Mocap.Imu (it
                 would be Assembly-CSharp, built where the package's assemblies are not)
  modules        every built-in module the C# code uses (Physics, ArticulationBody, Animator,
                 AvatarBuilder, GUI, XRSettings...; outside engine-free assemblies, samples
                 included) is a dependency at "1.0.0", and every declared module is used; a
                 package with test assemblies depends on com.unity.test-framework
  plugins        .so/.dll/.dylib/.bundle live under Runtime/Plugins/<OS>/..., have a
                 PluginImporter .meta with the editor and player platform of their OS enabled;
                 none is tracked by git (they are build outputs: scripts/build_native_plugin.sh)

Usage: scripts/package_lint.py [--package DIR] [--no-git]
"""

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import unity_meta  # noqa: E402

KNOWN_UNITY_ASSEMBLIES = {"UnityEngine.TestRunner", "UnityEditor.TestRunner"}
EXPECTED_ASSEMBLIES = {
    "Mocap.Imu.Core": "Runtime/Core",
    "Mocap.Imu": "Runtime",
    "Mocap.Imu.Editor": "Editor",
    "Mocap.Imu.Tests.Editor": "Tests/Editor",
    "Mocap.Imu.Tests.Runtime": "Tests/Runtime",
}
REQUIRED_FILES = ["package.json", "README.md", "CHANGELOG.md", "LICENSE.md",
                  "Third Party Notices.md"]
REQUIRED_DIRS = ["Runtime", "Editor", "Tests/Editor", "Tests/Runtime"]
# Where each kind of native plugin must live and which platforms its .meta must enable.
PLUGIN_RULES = {
    ".so": ("Runtime/Plugins/Linux/", "Linux", "Linux64"),
    ".dll": ("Runtime/Plugins/Windows/", "Windows", "Win64"),
    ".dylib": ("Runtime/Plugins/macOS/", "OSX", "OSXUniversal"),
    ".bundle": ("Runtime/Plugins/macOS/", "OSX", "OSXUniversal"),
}
# Platform names of asmdef includePlatforms/excludePlatforms (UnityEditor.Compilation's
# AssemblyDefinitionPlatform.Name values).
UNITY_PLATFORMS = {
    "Android", "CloudRendering", "Editor", "EmbeddedLinux", "GameCoreScarlett", "GameCoreXboxOne",
    "iOS", "LinuxStandalone64", "Lumin", "macOSStandalone", "PS4", "PS5", "QNX", "Stadia",
    "Switch", "tvOS", "VisionOS", "WebGL", "WindowsStandalone32", "WindowsStandalone64", "WSA",
    "XboxOne",
}
# The asmdef platform of each player a native plugin is built for (see PLUGIN_RULES), plus the
# Editor: where an assembly that calls the engine may compile.
NATIVE_PLATFORMS = {"Editor", "LinuxStandalone64", "WindowsStandalone64", "macOSStandalone"}
# Built-in module -> the API names (whole words, in code outside comments and strings) that live
# in it. Names of the engine-free core (its own HumanBone, say) are not scanned.
MODULE_APIS = {
    "com.unity.modules.physics": r"Physics|Rigidbody|Collider|BoxCollider|SphereCollider|"
                                 r"CapsuleCollider|MeshCollider|CharacterController|RaycastHit|"
                                 r"ArticulationBody|ArticulationDrive|ArticulationJointType|"
                                 r"ArticulationDofLock|ConfigurableJoint|PhysicMaterial",
    "com.unity.modules.animation": r"Animator|Avatar|AvatarBuilder|HumanBodyBones|HumanDescription|"
                                   r"SkeletonBone|HumanPose|HumanPoseHandler|AnimationClip|"
                                   r"RuntimeAnimatorController",
    "com.unity.modules.imgui": r"GUI|GUILayout|GUIStyle|GUIContent|GUISkin|GUIUtility|OnGUI",
    "com.unity.modules.jsonserialize": r"JsonUtility",
    "com.unity.modules.vr": r"XRSettings|XRDevice",
    "com.unity.modules.xr": r"InputDevices|InputDevice|XRInputSubsystem|XRDisplaySubsystem",
    "com.unity.modules.ui": r"Canvas|CanvasRenderer|CanvasGroup",
    "com.unity.modules.textrendering": r"TextMesh|Font",
    "com.unity.modules.audio": r"AudioSource|AudioClip|AudioListener",
    "com.unity.modules.unitywebrequest": r"UnityWebRequest",
}
MODULE_VERSION = "1.0.0"
TEST_FRAMEWORK = "com.unity.test-framework"
# Comments and string/char literals, so that a word in them is not taken for an API use.
CS_NOISE = re.compile(r'@"(?:[^"]|"")*"|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'|//[^\n]*|/\*.*?\*/',
                      re.S)
SEMVER = re.compile(r"^\d+\.\d+\.\d+(-[0-9A-Za-z.-]+)?(\+[0-9A-Za-z.-]+)?$")
PACKAGE_NAME = re.compile(r"^[a-z0-9][a-z0-9-]*(\.[a-z0-9][a-z0-9-]*){2,}$")


class Linter:
    def __init__(self, package: Path, use_git: bool):
        self.pkg = package
        self.use_git = use_git
        self.problems = []

    def fail(self, rel, msg):
        self.problems.append(f"{self.pkg / rel if rel else self.pkg}: {msg}")

    # ---------------------------------------------------------------------------------- json
    def load_json(self, rel):
        try:
            return json.loads((self.pkg / rel).read_text(encoding="utf-8"))
        except json.JSONDecodeError as e:
            self.fail(rel, f"invalid JSON: {e}")
        except OSError as e:
            self.fail(rel, f"cannot read: {e}")
        return None

    def check_json_files(self):
        for path in sorted(self.pkg.rglob("*")):
            rel = path.relative_to(self.pkg).as_posix()
            parts = rel.split("/")
            if parts[0] == "Native~" or any(p.startswith(".") for p in parts):
                continue
            if path.is_file() and path.suffix in (".json", ".asmdef", ".asmref"):
                if rel != "package.json":  # package.json is parsed (and reported) once
                    self.load_json(rel)

    # ---------------------------------------------------------------------------- package.json
    def check_manifest(self):
        if not (self.pkg / "package.json").is_file():
            self.fail("package.json", "missing")
            return
        m = self.load_json("package.json")
        if m is None:
            return
        if not isinstance(m, dict):
            self.fail("package.json", "top level must be an object")
            return
        for key in ("name", "version", "displayName", "description", "unity"):
            if not isinstance(m.get(key), str) or not m.get(key).strip():
                self.fail("package.json", f'"{key}" is missing or not a non-empty string')
        name = m.get("name")
        if isinstance(name, str) and not PACKAGE_NAME.match(name):
            self.fail("package.json", f'"name" {name!r} is not a reverse-domain lower-case name')
        if isinstance(name, str) and name != unity_meta.PACKAGE_NAME:
            self.fail("package.json", f'"name" {name!r} is not {unity_meta.PACKAGE_NAME!r} '
                      "(the package these tools and the samples are written for)")
        if isinstance(m.get("version"), str) and not SEMVER.match(m["version"]):
            self.fail("package.json", f'"version" {m["version"]!r} is not semver (x.y.z)')
        if isinstance(m.get("unity"), str) and not re.match(r"^\d{4}\.\d+$", m["unity"]):
            self.fail("package.json", f'"unity" {m["unity"]!r} is not like "2022.3"')
        kw = m.get("keywords")
        if not isinstance(kw, list) or not kw or not all(isinstance(k, str) for k in kw):
            self.fail("package.json", '"keywords" must be a non-empty list of strings')
        author = m.get("author")
        if not (isinstance(author, dict) and isinstance(author.get("name"), str)):
            self.fail("package.json", '"author" must be an object with a "name"')
        deps = m.get("dependencies", {})
        if not isinstance(deps, dict):
            self.fail("package.json", '"dependencies" must be an object')
        else:
            for dep, ver in deps.items():
                if not PACKAGE_NAME.match(dep) or not isinstance(ver, str) or not SEMVER.match(ver):
                    self.fail("package.json", f'dependency {dep!r}: {ver!r} is not name -> x.y.z')
        samples = m.get("samples", [])
        if not isinstance(samples, list):
            self.fail("package.json", '"samples" must be a list')
            samples = []
        for i, s in enumerate(samples):
            if not isinstance(s, dict):
                self.fail("package.json", f"samples[{i}] is not an object")
                continue
            for key in ("displayName", "description", "path"):
                if not isinstance(s.get(key), str) or not s.get(key):
                    self.fail("package.json", f'samples[{i}] has no "{key}"')
            path = s.get("path")
            if isinstance(path, str) and path:
                if not path.startswith("Samples~/"):
                    self.fail("package.json", f'samples[{i}] path {path!r} is not under "Samples~/"')
                if not (self.pkg / path).is_dir():
                    self.fail("package.json", f"samples[{i}] path {path!r} does not exist")
        self.manifest = m

    def check_layout(self):
        for rel in REQUIRED_FILES:
            if not (self.pkg / rel).is_file():
                self.fail(rel, "missing (Unity package layout)")
        for rel in REQUIRED_DIRS:
            if not (self.pkg / rel).is_dir():
                self.fail(rel, "missing folder (Unity package layout)")
        version = getattr(self, "manifest", {}).get("version")
        log = self.pkg / "CHANGELOG.md"
        if isinstance(version, str) and log.is_file():
            if not re.search(r"^## \[" + re.escape(version) + r"\]", log.read_text(encoding="utf-8"),
                             re.M):
                self.fail("CHANGELOG.md", f'no "## [{version}]" entry for the package version')

    # ---------------------------------------------------------------------------------- metas
    def check_metas(self):
        """Presence, orphans, importer settings, GUID format and uniqueness. A GUID is never
        compared with the asset's path: it must survive a move or a rename."""
        missing, stale, orphans = unity_meta.plan(self.pkg)
        for m in missing:
            self.fail(m[:-5], f"has no .meta file (expected {m}; run scripts/unity_meta.py)")
        for m in orphans:
            self.fail(m, f"orphan .meta: its asset {m[:-5]} does not exist")
        assets = dict(unity_meta.walk_assets(self.pkg))
        for m in stale:
            rel = m[:-5]
            self.fail(m, "importer settings differ from scripts/unity_meta.py's for a "
                      f"{'folder' if assets[rel] else Path(rel).suffix or 'file'} "
                      "(run scripts/unity_meta.py; it keeps the GUID)")
        guids = unity_meta.read_guids(self.pkg)
        for m, why in unity_meta.guid_problems(guids):
            self.fail(m, why)
        self.guids = {g: m for m, g in guids.items() if g}

    # -------------------------------------------------------------------------------- asmdefs
    def check_asmdefs(self):
        asmdefs = {}  # rel -> parsed
        for path in sorted(self.pkg.rglob("*.asmdef")):
            rel = path.relative_to(self.pkg).as_posix()
            if any(p.endswith("~") or p.startswith(".") for p in rel.split("/")[:-1]):
                continue
            data = self.load_json(rel)
            if isinstance(data, dict):
                asmdefs[rel] = data
            elif data is not None:
                self.fail(rel, "asmdef must be a JSON object")
        by_name = {}
        for rel, a in asmdefs.items():
            name = a.get("name")
            if not isinstance(name, str) or not name:
                self.fail(rel, 'asmdef has no "name"')
                continue
            if name in by_name:
                self.fail(rel, f"asmdef name {name!r} is also used by {by_name[name][0]}")
                continue
            by_name[name] = (rel, a)
        for name, folder in EXPECTED_ASSEMBLIES.items():
            if name not in by_name:
                self.fail(folder, f"assembly definition {name!r} is missing")
            elif Path(by_name[name][0]).parent.as_posix() != folder:
                self.fail(by_name[name][0], f"{name} is expected in {folder}/")
        guid_to_name = {}
        for name, (rel, _) in by_name.items():
            meta = self.pkg / (rel + ".meta")
            if meta.is_file():
                g = re.search(r"^guid: *(\S+)", meta.read_text(encoding="utf-8"), re.M)
                if g:
                    guid_to_name[g.group(1)] = name

        def editor_only(a):
            return a.get("includePlatforms") == ["Editor"]

        graph = {}
        for name, (rel, a) in by_name.items():
            refs = a.get("references", [])
            if not isinstance(refs, list):
                self.fail(rel, '"references" must be a list')
                refs = []
            resolved = []
            for r in refs:
                target = r
                if isinstance(r, str) and r.startswith("GUID:"):
                    target = guid_to_name.get(r[5:])
                    if target is None:
                        self.fail(rel, f"reference {r} is no asmdef GUID of this package")
                        continue
                if target in by_name:
                    resolved.append(target)
                    if not editor_only(a) and editor_only(by_name[target][1]):
                        self.fail(rel, f"player assembly {name} references Editor-only {target}")
                elif target not in KNOWN_UNITY_ASSEMBLIES:
                    self.fail(rel, f"reference {r!r} resolves to no asmdef of the package nor a "
                              f"known Unity assembly ({', '.join(sorted(KNOWN_UNITY_ASSEMBLIES))})")
            graph[name] = resolved
            self.check_asmdef_rules(rel, name, a)
        # cycles
        state = {}

        def visit(n, stack):
            state[n] = 1
            for t in graph.get(n, []):
                if state.get(t) == 1:
                    self.fail(by_name[n][0], "reference cycle: " + " -> ".join(stack + [n, t]))
                elif t not in state:
                    visit(t, stack + [n])
            state[n] = 2

        for n in sorted(graph):
            if n not in state:
                visit(n, [])
        self.check_scripts_owned(sorted(Path(r).parent.as_posix() for r in asmdefs))
        self.asmdef_platforms, self.asmdef_native = self.check_platforms(by_name, graph)
        self.asmdefs = by_name
        self.asmdef_guids = guid_to_name
        self.asmdef_graph = graph

    def platforms_of(self, rel, a):
        """The platforms an asmdef compiles on (Unity's names), checking the two lists."""
        lists = {}
        for key in ("includePlatforms", "excludePlatforms"):
            value = a.get(key, [])
            if not isinstance(value, list) or not all(isinstance(p, str) for p in value):
                self.fail(rel, f'"{key}" must be a list of platform names')
                value = []
            for p in value:
                if p not in UNITY_PLATFORMS:
                    self.fail(rel, f'"{key}" names {p!r}, which is no Unity platform '
                              f"(asmdef names: {', '.join(sorted(UNITY_PLATFORMS))})")
            lists[key] = set(value) & UNITY_PLATFORMS
        if lists["includePlatforms"] and lists["excludePlatforms"]:
            self.fail(rel, "includePlatforms and excludePlatforms are both set (Unity allows one)")
        if lists["includePlatforms"]:
            return lists["includePlatforms"]
        return UNITY_PLATFORMS - lists["excludePlatforms"]

    def calls_native(self, folder):
        """Whether an assembly's own scripts (not those of nested asmdefs) declare a DllImport."""
        for cs in sorted((self.pkg / folder).rglob("*.cs")):
            owner = cs.parent
            while owner != self.pkg / folder and not any(owner.glob("*.asmdef")):
                owner = owner.parent
            if owner != self.pkg / folder:
                continue
            if re.search(r"\[\s*(System\.Runtime\.InteropServices\.)?DllImport\b",
                         CS_NOISE.sub(" ", cs.read_text(encoding="utf-8", errors="replace"))):
                return True
        return False

    def native_assemblies(self, by_name, graph, known=frozenset()):
        """The assemblies that call the engine (own DllImport) or reference one that does."""
        native = {n for n, (rel, _) in by_name.items() if self.calls_native(Path(rel).parent)}
        native |= set(known)
        changed = True
        while changed:  # an assembly that references a native one needs the engine too
            before = len(native)
            native |= {n for n in graph if any(t in native for t in graph[n])}
            changed = len(native) != before
        return native

    def check_platforms(self, by_name, graph, known_platforms=None, known_native=frozenset()):
        """Engine users limited to the plugin platforms; no platform a reference lacks. The
        known_ arguments hold what is already decided for assemblies outside by_name. Returns
        the platforms of every assembly and the set of those that need the engine."""
        platforms = dict(known_platforms or {})
        platforms.update({n: self.platforms_of(rel, a) for n, (rel, a) in by_name.items()})
        native = self.native_assemblies(by_name, graph, known_native)
        for name in sorted(by_name):
            rel, _ = by_name[name]
            if name in native:
                outside = platforms[name] - NATIVE_PLATFORMS
                if outside:
                    self.fail(rel, f"{name} needs the native engine but compiles for "
                              f"{', '.join(sorted(outside))}, where no plugin is built: set "
                              f"includePlatforms to (some of) {', '.join(sorted(NATIVE_PLATFORMS))}")
            for target in graph.get(name, []):
                missing = platforms[name] - platforms[target]
                if missing:
                    self.fail(rel, f"{name} compiles for {', '.join(sorted(missing))}, where its "
                              f"reference {target} does not")
        return platforms, native

    def check_asmdef_rules(self, rel, name, a):
        folder = Path(rel).parent.as_posix()
        is_test = folder == "Tests" or folder.startswith("Tests/")
        if is_test:
            if "UNITY_INCLUDE_TESTS" not in (a.get("defineConstraints") or []):
                self.fail(rel, 'test assembly lacks defineConstraints ["UNITY_INCLUDE_TESTS"]')
            if a.get("overrideReferences") is not True:
                self.fail(rel, 'test assembly needs "overrideReferences": true')
            if "nunit.framework.dll" not in (a.get("precompiledReferences") or []):
                self.fail(rel, 'test assembly needs precompiledReferences ["nunit.framework.dll"]')
            for r in ("UnityEngine.TestRunner", "UnityEditor.TestRunner"):
                if r not in (a.get("references") or []):
                    self.fail(rel, f"test assembly does not reference {r}")
            if a.get("autoReferenced") is not False:
                self.fail(rel, 'test assembly should set "autoReferenced": false')
            if (folder == "Tests/Editor" or folder.startswith("Tests/Editor/")) and \
                    a.get("includePlatforms") != ["Editor"]:
                self.fail(rel, 'Editor test assembly must have includePlatforms ["Editor"]')
        if (folder == "Editor" or folder.startswith("Editor/")) and \
                a.get("includePlatforms") != ["Editor"]:
            self.fail(rel, 'Editor assembly must have includePlatforms ["Editor"]')
        if name == "Mocap.Imu.Core":
            if a.get("noEngineReferences") is not True:
                self.fail(rel, 'the engine-free core needs "noEngineReferences": true')
            for cs in sorted((self.pkg / folder).rglob("*.cs")):
                text = cs.read_text(encoding="utf-8", errors="replace")
                if re.search(r"^\s*using\s+(static\s+)?Unity(Engine|Editor)\b", text, re.M):
                    self.fail(cs.relative_to(self.pkg).as_posix(),
                              "uses UnityEngine/UnityEditor inside the engine-free core")

    # -------------------------------------------------------------------------------- samples
    def sample_folders(self):
        samples = getattr(self, "manifest", {}).get("samples", [])
        if not isinstance(samples, list):
            return []
        return [s["path"].rstrip("/") for s in samples
                if isinstance(s, dict) and isinstance(s.get("path"), str)
                and s["path"].startswith("Samples~/") and (self.pkg / s["path"]).is_dir()]

    def sample_assets(self, folder, pattern):
        """Files of a sample Unity imports once it is copied under Assets/ (none in its ~ or
        hidden folders), as (path relative to the package, path inside the sample)."""
        for path in sorted((self.pkg / folder).rglob(pattern)):
            inner = path.relative_to(self.pkg / folder)
            if not any(p.endswith("~") or p.startswith(".") for p in inner.parts):
                yield path.relative_to(self.pkg).as_posix(), inner

    def check_samples(self):
        package = getattr(self, "asmdefs", None)
        if package is None:
            return
        where = {name: rel for name, (rel, _) in package.items()}
        samples = {}
        for folder in self.sample_folders():
            own = {}
            for rel, inner in self.sample_assets(folder, "*.asmdef"):
                try:
                    a = json.loads((self.pkg / rel).read_text(encoding="utf-8"))
                except (json.JSONDecodeError, OSError):
                    continue  # reported by check_json_files
                name = a.get("name") if isinstance(a, dict) else None
                if not isinstance(name, str) or not name:
                    self.fail(rel, 'asmdef has no "name"')
                elif name in where:
                    self.fail(rel, f"asmdef name {name!r} is also used by {where[name]} (a user "
                              "importing both could not compile)")
                else:
                    where[name] = rel
                    own[name] = (rel, a)
            samples[folder] = own
        for folder, own in samples.items():
            self.check_sample_asmdefs(folder, own, samples)
            self.check_sample_scripts(folder, own)

    def check_sample_asmdefs(self, folder, own, samples):
        package = self.asmdefs
        others = {n: f for f, o in samples.items() if f != folder for n in o}
        graph = {}
        for name, (rel, a) in own.items():
            refs = a.get("references", [])
            if not isinstance(refs, list):
                self.fail(rel, '"references" must be a list')
                refs = []
            graph[name] = []
            for r in refs:
                if not isinstance(r, str):
                    self.fail(rel, f"reference {r!r} is not a string")
                    continue
                target = r
                if r.startswith("GUID:"):
                    target = self.asmdef_guids.get(r[5:])  # samples have no .meta: package only
                if target in own or target in package:
                    graph[name].append(target)
                    referenced = (own.get(target) or package.get(target))[1]
                    if a.get("includePlatforms") != ["Editor"] and \
                            referenced.get("includePlatforms") == ["Editor"]:
                        self.fail(rel, f"player assembly {name} references Editor-only {target}")
                elif target in others:
                    self.fail(rel, f"reference {r!r} is an asmdef of {others[target]}: a project may "
                              "have imported this sample alone")
                elif target not in KNOWN_UNITY_ASSEMBLIES:
                    self.fail(rel, f"reference {r!r} resolves to no asmdef of the package or of "
                              "this sample nor a known Unity assembly "
                              f"({', '.join(sorted(KNOWN_UNITY_ASSEMBLIES))})")
            in_editor_folder = "Editor" in Path(rel).relative_to(folder).parts[:-1]
            if in_editor_folder and a.get("includePlatforms") != ["Editor"]:
                self.fail(rel, 'Editor assembly must have includePlatforms ["Editor"]')
        self.check_platforms(own, graph, self.asmdef_platforms, self.asmdef_native)

    def check_sample_scripts(self, folder, own):
        asmdef_dirs = [Path(rel).parent for rel, _ in own.values()]
        for rel, inner in self.sample_assets(folder, "*.cs"):
            if any(d in Path(rel).parents for d in asmdef_dirs) or "Editor" in inner.parts[:-1]:
                continue
            code = CS_NOISE.sub(" ", (self.pkg / rel).read_text(encoding="utf-8", errors="replace"))
            if re.search(r"\bMocap\.Imu\b", code):
                self.fail(rel, "uses Mocap.Imu outside an asmdef of its sample: imported, it "
                          "compiles into Assembly-CSharp for every platform, but the package's "
                          f"assemblies exist only for {', '.join(sorted(NATIVE_PLATFORMS))}; give "
                          "the sample an asmdef with those includePlatforms")

    def check_scripts_owned(self, asmdef_dirs):
        for cs in sorted(self.pkg.rglob("*.cs")):
            rel = cs.relative_to(self.pkg).as_posix()
            if any(p.endswith("~") or p.startswith(".") for p in rel.split("/")):
                continue
            if not any(d == "." or rel.startswith(d + "/") for d in asmdef_dirs):
                self.fail(rel, "C# script outside every assembly definition")

    # -------------------------------------------------------------------------------- plugins
    def check_plugins(self):
        plugins = []
        for rel, is_dir in unity_meta.walk_assets(self.pkg):
            ext = Path(rel).suffix.lower()
            if not is_dir and ext in PLUGIN_RULES:
                plugins.append((rel, ext))
        for rel, ext in plugins:
            folder, editor_os, player = PLUGIN_RULES[ext]
            if not rel.startswith(folder):
                self.fail(rel, f"{ext} native plugin must live under {folder}")
            meta = self.pkg / (rel + ".meta")
            if not meta.is_file():
                continue  # already reported by check_metas
            tree = parse_meta(meta.read_text(encoding="utf-8", errors="replace"))
            imp = tree.get("PluginImporter")
            if not isinstance(imp, dict):
                self.fail(rel + ".meta", "native plugin .meta has no PluginImporter section")
                continue
            pdata = imp.get("platformData")
            if not isinstance(pdata, dict) or not pdata:
                self.fail(rel + ".meta", "PluginImporter has no platformData (platform settings)")
                continue
            enabled = {p for p, v in pdata.items()
                       if isinstance(v, dict) and str(v.get("enabled")) == "1"}
            if not enabled - {"Any"}:
                self.fail(rel + ".meta", "PluginImporter enables no platform")
            ed = pdata.get("Editor")
            if "Editor" not in enabled or not isinstance(ed, dict) or \
                    not isinstance(ed.get("settings"), dict) or ed["settings"].get("OS") != editor_os:
                self.fail(rel + ".meta", f"PluginImporter must enable the Editor on {editor_os}")
            if player not in enabled:
                self.fail(rel + ".meta", f"PluginImporter must enable the {player} player")
        if self.use_git:
            self.check_untracked_binaries([r for r, _ in plugins])

    def check_untracked_binaries(self, plugins):
        """Decision: native plugins are build outputs, never committed (see Documentation~)."""
        try:
            out = subprocess.run(
                ["git", "-C", str(self.pkg), "ls-files", "--", "Runtime/Plugins"],
                capture_output=True, text=True, timeout=30)
        except (OSError, subprocess.SubprocessError):
            return
        if out.returncode != 0:
            return  # not a git checkout (an installed copy): nothing to compare
        for line in out.stdout.splitlines():
            self.fail(line, "tracked by git: Runtime/Plugins/ holds build outputs "
                      "(scripts/build_native_plugin.sh); remove it from the index")
        for rel in plugins:
            ign = subprocess.run(["git", "-C", str(self.pkg), "check-ignore", "-q", rel],
                                 capture_output=True, timeout=30)
            if ign.returncode == 1:
                self.fail(rel, "native plugin is not ignored by .gitignore (it is a build output)")

    # -------------------------------------------------------------------------------- modules
    def scripts_using_unity(self):
        """Every .cs Unity compiles or a user imports (samples), outside engine-free assemblies."""
        engine_free = [Path(rel).parent for rel, a in getattr(self, "asmdefs", {}).values()
                       if a.get("noEngineReferences") is True]
        for cs in sorted(self.pkg.rglob("*.cs")):
            rel = cs.relative_to(self.pkg)
            parts = rel.parts
            if parts[0] == "Native~" or any(p.startswith(".") for p in parts):
                continue
            if any(rel.parent == d or d in rel.parents for d in engine_free):
                continue
            yield rel.as_posix(), CS_NOISE.sub(" ", cs.read_text(encoding="utf-8", errors="replace"))

    def check_modules(self):
        manifest = getattr(self, "manifest", None)
        if not isinstance(manifest, dict) or not isinstance(manifest.get("dependencies", {}), dict):
            return  # already reported
        deps = manifest.get("dependencies", {})
        users = {}
        patterns = {m: re.compile(r"\b(" + names + r")\b") for m, names in MODULE_APIS.items()}
        for rel, code in self.scripts_using_unity():
            for module, pattern in patterns.items():
                found = pattern.search(code)
                if found and module not in users:
                    users[module] = (rel, found.group(1))
        for module, (rel, api) in sorted(users.items()):
            if module not in deps:
                self.fail("package.json", f"{rel} uses {api} (built-in module {module}), which "
                          f'"dependencies" does not declare ("{module}": "{MODULE_VERSION}")')
        for dep, version in sorted(deps.items()):
            if not dep.startswith("com.unity.modules."):
                continue
            if version != MODULE_VERSION:
                self.fail("package.json", f'built-in module {dep} must be "{MODULE_VERSION}", '
                          f"not {version!r}")
            if dep in MODULE_APIS and dep not in users:
                self.fail("package.json", f"declares {dep}, which no script of the package uses")
        test_assemblies = sorted(rel for rel, a in getattr(self, "asmdefs", {}).values()
                                 if {"UnityEngine.TestRunner", "UnityEditor.TestRunner"}
                                 & set(a.get("references") or []))
        if test_assemblies and TEST_FRAMEWORK not in deps:
            self.fail("package.json", f"{test_assemblies[0]} is a test assembly (users run it via "
                      f'"testables"), so "dependencies" needs {TEST_FRAMEWORK}')

    def run(self):
        self.check_manifest()
        self.check_layout()
        self.check_json_files()
        self.check_metas()
        self.check_asmdefs()
        self.check_samples()
        self.check_plugins()
        self.check_modules()
        return self.problems


def parse_meta(text):
    """A minimal reader for Unity's block-style .meta YAML: nested mappings by indentation;
    scalars stay strings; flow values ({}, []) and list items are kept as strings."""
    root = {}
    stack = [(-1, root)]
    for raw in text.splitlines():
        if not raw.strip() or raw.lstrip().startswith("#") or raw.lstrip().startswith("- "):
            continue
        indent = len(raw) - len(raw.lstrip(" "))
        line = raw.strip()
        if ":" not in line:
            continue
        key, _, value = line.partition(":")
        while stack and stack[-1][0] >= indent:
            stack.pop()
        parent = stack[-1][1]
        value = value.strip()
        if value == "":
            child = {}
            parent[key.strip()] = child
            stack.append((indent, child))
        else:
            parent[key.strip()] = value
    return root


def lint(package: Path, use_git: bool = True):
    return Linter(package.resolve(), use_git).run()


def main(argv=None):
    ap = argparse.ArgumentParser(description="Lint the com.mocap.imu Unity package.")
    ap.add_argument("--package", type=Path, default=unity_meta.DEFAULT_PACKAGE)
    ap.add_argument("--no-git", action="store_true", help="skip the git-tracking checks")
    args = ap.parse_args(argv)
    problems = lint(args.package, use_git=not args.no_git)
    for p in problems:
        print(p)
    print(f"package_lint: {len(problems)} problem(s) in {args.package.resolve()}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
