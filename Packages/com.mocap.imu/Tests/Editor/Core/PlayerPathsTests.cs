// PlayerPaths on real folders laid out like a project in the editor and like each platform's
// player build (Windows <Game>_Data, Linux <Game>_Data, macOS <Game>.app/Contents), with the
// files present and missing. SerialPortDefaults on the port names each OS gives USB-serial bridges.

using System;
using System.Collections.Generic;
using System.IO;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    public sealed class PlayerPathsTests
    {
        const string ModelName = "mocap_pose_int8.onnx";

        static string Touch(string root, params string[] parts)
        {
            var path = Path.Combine(root, Path.Combine(parts));
            Directory.CreateDirectory(Path.GetDirectoryName(path));
            File.WriteAllText(path, "x");
            return Path.GetFullPath(path);
        }

        // ---- editor --------------------------------------------------------------------------

        [Test]
        public void EditorResolvesTheDefaultModelInsideTheProjectsPackagesFolder()
        {
            var project = TestPaths.NewTempDirectory("project");
            var model = Touch(project, "Packages", "com.mocap.imu", "Runtime", "Models", ModelName);
            var lookup = PlayerPaths.FindModel(RunningContext.Editor(HostOs.Linux, project), null);
            Assert.That(lookup.Found, Is.True, lookup.Error);
            Assert.That(lookup.Path, Is.EqualTo(model));
            Assert.That(lookup.Error, Is.Null);
        }

        [Test]
        public void EditorResolvesPackagesPathsAgainstAPackageFolderOutsideTheProject()
        {
            // A registry package lives in Library/PackageCache/name@hash, not under Packages/.
            var project = TestPaths.NewTempDirectory("project");
            var cache = Path.Combine(project, "Library", "PackageCache", "com.mocap.imu@1a2b3c");
            var model = Touch(cache, "Runtime", "Models", ModelName);
            var editor = RunningContext.Editor(HostOs.Windows, project);
            editor.PackageFolders["com.mocap.imu"] = cache;
            var lookup = PlayerPaths.FindModel(editor, PlayerPaths.DefaultModelPath);
            Assert.That(lookup.Path, Is.EqualTo(model));
        }

        [Test]
        public void EditorResolvesAssetsPathsAgainstTheProjectAndTakesAbsolutePathsAsTheyAre()
        {
            var project = TestPaths.NewTempDirectory("project");
            var inAssets = Touch(project, "Assets", "Models", "mine.onnx");
            var elsewhere = Touch(TestPaths.NewTempDirectory("elsewhere"), "other.onnx");
            var editor = RunningContext.Editor(HostOs.MacOS, project);
            Assert.That(PlayerPaths.FindModel(editor, "Assets/Models/mine.onnx").Path, Is.EqualTo(inAssets));
            Assert.That(PlayerPaths.FindModel(editor, elsewhere).Path, Is.EqualTo(elsewhere));
        }

        [Test]
        public void EditorMissingModelNamesThePathTried()
        {
            var project = TestPaths.NewTempDirectory("project");
            var lookup = PlayerPaths.FindModel(RunningContext.Editor(HostOs.Linux, project), "Assets/none.onnx");
            Assert.That(lookup.Found, Is.False);
            Assert.That(lookup.Tried, Is.EqualTo(new[] { Path.Combine(project, "Assets", "none.onnx") }));
            StringAssert.Contains("pose model was not found", lookup.Error);
            StringAssert.Contains(Path.Combine(project, "Assets", "none.onnx"), lookup.Error);
            var e = Assert.Throws<MocapException>(() => lookup.Require());
            Assert.That(e.Status, Is.EqualTo(MocapStatus.NotFound));
        }

        [TestCase(HostOs.Windows, HostArchitecture.X64, "Windows/x64/onnxruntime.dll")]
        [TestCase(HostOs.Windows, HostArchitecture.Arm64, "Windows/arm64/onnxruntime.dll")]
        [TestCase(HostOs.Linux, HostArchitecture.X64, "Linux/x64/libonnxruntime.so")]
        [TestCase(HostOs.MacOS, HostArchitecture.Arm64, "macOS/arm64/libonnxruntime.dylib")]
        public void EditorFindsTheOnnxRuntimePluginOfItsPlatform(HostOs os, HostArchitecture cpu, string inPlugins)
        {
            // Every platform's plugin present: the one picked must be this platform's.
            var project = TestPaths.NewTempDirectory("project");
            var plugins = Path.Combine(project, "Packages", PlayerPaths.OnnxRuntimePackage, "Plugins");
            foreach (var each in new[] { "Windows/x64/onnxruntime.dll", "Windows/arm64/onnxruntime.dll",
                                         "Linux/x64/libonnxruntime.so", "macOS/arm64/libonnxruntime.dylib" })
                Touch(plugins, each.Split('/'));
            var lookup = PlayerPaths.FindOnnxRuntime(RunningContext.Editor(os, project, cpu));
            Assert.That(lookup.Path, Is.EqualTo(Path.GetFullPath(Path.Combine(plugins, Path.Combine(inPlugins.Split('/'))))));
        }

        [Test]
        public void IntelMacEditorHasNoPluginAndSaysWhy()
        {
            var project = TestPaths.NewTempDirectory("project");
            Touch(project, "Packages", PlayerPaths.OnnxRuntimePackage, "Plugins", "macOS", "arm64", "libonnxruntime.dylib");
            var lookup = PlayerPaths.FindOnnxRuntime(RunningContext.Editor(HostOs.MacOS, project, HostArchitecture.X64));
            Assert.That(lookup.Found, Is.False);
            Assert.That(lookup.Tried, Is.Empty);
            StringAssert.Contains("Apple silicon only", lookup.Error);
        }

        [Test]
        public void OnnxRuntimeOverrideIsTheOnlyCandidate()
        {
            var project = TestPaths.NewTempDirectory("project");
            Touch(project, "Packages", PlayerPaths.OnnxRuntimePackage, "Plugins", "Linux", "x64", "libonnxruntime.so");
            var editor = RunningContext.Editor(HostOs.Linux, project);
            editor.OnnxRuntimeOverride = Path.Combine(project, "custom", "libonnxruntime.so");
            var missing = PlayerPaths.FindOnnxRuntime(editor);
            Assert.That(missing.Found, Is.False, "the package plugin must not be used when the override is set");
            StringAssert.Contains(editor.OnnxRuntimeOverride, missing.Error);
            StringAssert.Contains("MOCAP_ONNXRUNTIME_PATH", missing.Error);
            var custom = Touch(project, "custom", "libonnxruntime.so");
            Assert.That(PlayerPaths.FindOnnxRuntime(editor).Path, Is.EqualTo(custom));
        }

        [Test]
        public void ExplicitOnnxRuntimePathResolvesAgainstProjectInEditorAndDataInPlayer()
        {
            var project = TestPaths.NewTempDirectory("project");
            var inProject = Touch(project, "Native", "libonnxruntime.so");
            Assert.That(PlayerPaths.FindOnnxRuntime(RunningContext.Editor(HostOs.Linux, project), "Native/libonnxruntime.so").Path,
                        Is.EqualTo(inProject));
            var data = Path.Combine(TestPaths.NewTempDirectory("build"), "Game_Data");
            var inData = Touch(data, "Native", "libonnxruntime.so");
            Assert.That(PlayerPaths.FindOnnxRuntime(RunningContext.Player(HostOs.Linux, data), "Native/libonnxruntime.so").Path,
                        Is.EqualTo(inData));
        }

        // ---- players -------------------------------------------------------------------------

        /// <summary>A build folder laid out like a player of <paramref name="os"/>; returns Application.dataPath.</summary>
        static string PlayerDataFolder(HostOs os, string build) => os switch
        {
            HostOs.MacOS => Path.Combine(build, "Game.app", "Contents"),
            _ => Path.Combine(build, "Game_Data"),
        };

        [TestCase(HostOs.Windows, "Game_Data/StreamingAssets")]
        [TestCase(HostOs.Linux, "Game_Data/StreamingAssets")]
        [TestCase(HostOs.MacOS, "Game.app/Contents/Resources/Data/StreamingAssets")]
        public void PlayerStreamingAssetsSitWhereUnityPutsThem(HostOs os, string expected)
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(os, PlayerDataFolder(os, build));
            Assert.That(player.StreamingAssetsPath, Is.EqualTo(Path.Combine(build, Path.Combine(expected.Split('/')))));
        }

        [TestCase(HostOs.Windows)]
        [TestCase(HostOs.Linux)]
        [TestCase(HostOs.MacOS)]
        public void PlayerReadsTheDefaultModelFromItsStreamingAssetsFolder(HostOs os)
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(os, PlayerDataFolder(os, build));
            var missing = PlayerPaths.FindModel(player, PlayerPaths.DefaultModelPath);
            Assert.That(missing.Found, Is.False);
            var expected = Path.Combine(player.StreamingAssetsPath, PlayerPaths.StreamingFolderName, ModelName);
            Assert.That(missing.Tried[0], Is.EqualTo(expected));
            StringAssert.Contains(expected, missing.Error);
            Assert.That(missing.Tried, Has.None.Contains("Packages"), "a player has no Packages folder to look in");

            var model = Touch(player.StreamingAssetsPath, PlayerPaths.StreamingFolderName, ModelName);
            Assert.That(PlayerPaths.FindModel(player, PlayerPaths.DefaultModelPath).Path, Is.EqualTo(model));
        }

        [Test]
        public void PlayerFindsAModelPlacedByHandUnderStreamingAssets()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.Linux, PlayerDataFolder(HostOs.Linux, build));
            var nested = Touch(player.StreamingAssetsPath, "Models", "custom.onnx");
            Assert.That(PlayerPaths.FindModel(player, "Models/custom.onnx").Path, Is.EqualTo(nested));
            var bare = Touch(player.StreamingAssetsPath, "bare.onnx");
            Assert.That(PlayerPaths.FindModel(player, "Assets/Somewhere/bare.onnx").Path, Is.EqualTo(bare));
        }

        [Test]
        public void PlayerPrefersTheBuildCopyOverAHandPlacedOne()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.Windows, PlayerDataFolder(HostOs.Windows, build));
            Touch(player.StreamingAssetsPath, ModelName);
            var copied = Touch(player.StreamingAssetsPath, PlayerPaths.StreamingFolderName, ModelName);
            Assert.That(PlayerPaths.FindModel(player, null).Path, Is.EqualTo(copied));
        }

        [Test]
        public void PlayerWithAnAbsoluteModelPathFallsBackToTheBuildCopy()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.MacOS, PlayerDataFolder(HostOs.MacOS, build));
            var gone = Path.Combine(TestPaths.NewTempDirectory("dev"), "my_model.onnx");
            var copied = Touch(player.StreamingAssetsPath, PlayerPaths.StreamingFolderName, "my_model.onnx");
            var lookup = PlayerPaths.FindModel(player, gone);
            Assert.That(lookup.Tried[0], Is.EqualTo(gone));
            Assert.That(lookup.Path, Is.EqualTo(copied));
        }

        [TestCase(HostOs.Windows, HostArchitecture.X64, "Game_Data/Plugins/x86_64/onnxruntime.dll")]
        [TestCase(HostOs.Windows, HostArchitecture.Arm64, "Game_Data/Plugins/ARM64/onnxruntime.dll")]
        [TestCase(HostOs.Linux, HostArchitecture.X64, "Game_Data/Plugins/libonnxruntime.so")]
        [TestCase(HostOs.MacOS, HostArchitecture.Arm64, "Game.app/Contents/PlugIns/libonnxruntime.dylib")]
        public void PlayerFindsOnnxRuntimeInItsPluginsFolder(HostOs os, HostArchitecture cpu, string relative)
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(os, PlayerDataFolder(os, build), cpu);
            var missing = PlayerPaths.FindOnnxRuntime(player);
            Assert.That(missing.Found, Is.False);
            var expected = Path.Combine(build, Path.Combine(relative.Split('/')));
            Assert.That(missing.Tried[0], Is.EqualTo(expected));
            StringAssert.Contains(expected, missing.Error);

            Touch(build, relative.Split('/'));
            Assert.That(PlayerPaths.FindOnnxRuntime(player).Path, Is.EqualTo(expected));
        }

        [Test]
        public void LinuxPlayerAlsoLooksInTheArchitectureSubfolder()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.Linux, PlayerDataFolder(HostOs.Linux, build));
            var library = Touch(build, "Game_Data", "Plugins", "x86_64", "libonnxruntime.so");
            Assert.That(PlayerPaths.FindOnnxRuntime(player).Path, Is.EqualTo(library));
        }

        [Test]
        public void PlayerNeverLooksInsideTheEditorsPackageFolders()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.Linux, PlayerDataFolder(HostOs.Linux, build));
            foreach (var candidate in PlayerPaths.OnnxRuntimeCandidates(player, null, out _))
            {
                StringAssert.StartsWith(player.DataPath, candidate);
                StringAssert.DoesNotContain(PlayerPaths.OnnxRuntimePackage, candidate);
            }
        }

        // ---- other data files ---------------------------------------------------------------

        [Test]
        public void DataFilesResolveAgainstTheProjectInTheEditor()
        {
            var project = TestPaths.NewTempDirectory("project");
            var capture = Touch(project, "Packages", "com.mocap.imu", "Tests", "Runtime", "Fixtures", "walk.cap");
            var editor = RunningContext.Editor(HostOs.Linux, project);
            Assert.That(PlayerPaths.FindFile(editor, "Packages/com.mocap.imu/Tests/Runtime/Fixtures/walk.cap", "capture").Path, Is.EqualTo(capture));
            var missing = PlayerPaths.FindFile(editor, "Captures/none.cap", "capture");
            StringAssert.StartsWith("the capture was not found", missing.Error);
            StringAssert.Contains(Path.Combine(project, "Captures", "none.cap"), missing.Error);
            Assert.Throws<ArgumentException>(() => PlayerPaths.FindFile(editor, " ", "capture"));
        }

        [Test]
        public void PlayerDataFilesComeFromPersistentDataThenStreamingAssets()
        {
            var build = TestPaths.NewTempDirectory("build");
            var player = RunningContext.Player(HostOs.Windows, PlayerDataFolder(HostOs.Windows, build));
            player.PersistentDataPath = Path.Combine(TestPaths.NewTempDirectory("appdata"), "Company", "Game");
            var missing = PlayerPaths.FindFile(player, "Captures/take.cap", "capture");
            Assert.That(missing.Tried, Is.EqualTo(new[]
            {
                Path.Combine(player.PersistentDataPath, "Captures", "take.cap"),
                Path.Combine(player.StreamingAssetsPath, "Captures", "take.cap"),
                Path.Combine(player.StreamingAssetsPath, "take.cap"),
            }));
            var shipped = Touch(player.StreamingAssetsPath, "take.cap");
            Assert.That(PlayerPaths.FindFile(player, "Captures/take.cap", "capture").Path, Is.EqualTo(shipped));
            var recorded = Touch(player.PersistentDataPath, "Captures", "take.cap");
            Assert.That(PlayerPaths.FindFile(player, "Captures/take.cap", "capture").Path, Is.EqualTo(recorded));
        }

        [Test]
        public void RecordingsGoUnderTheProjectOrPersistentData()
        {
            var project = TestPaths.NewTempDirectory("project");
            Assert.That(PlayerPaths.RecordingFolder(RunningContext.Editor(HostOs.Linux, project), ""),
                        Is.EqualTo(Path.Combine(project, "Captures")));
            var player = RunningContext.Player(HostOs.MacOS, Path.Combine(project, "Game.app", "Contents"));
            Assert.Throws<ArgumentException>(() => PlayerPaths.RecordingFolder(player, "Takes"));
            player.PersistentDataPath = Path.Combine(project, "Support");
            Assert.That(PlayerPaths.RecordingFolder(player, "Takes"), Is.EqualTo(Path.Combine(project, "Support", "Takes")));
            var absolute = Path.Combine(project, "Elsewhere");
            Assert.That(PlayerPaths.RecordingFolder(player, absolute), Is.EqualTo(absolute));
        }

        [Test]
        public void CurrentOsAndArchitectureAreThisMachines()
        {
            var expectedOs = Environment.OSVersion.Platform == PlatformID.Win32NT ? HostOs.Windows
                           : File.Exists("/System/Library/CoreServices/SystemVersion.plist") ? HostOs.MacOS
                           : HostOs.Linux;
            Assert.That(PlayerPaths.CurrentOs(), Is.EqualTo(expectedOs));
            Assert.That(PlayerPaths.CurrentArchitecture(),
                        Is.EqualTo(IntPtr.Size == 8 && System.Runtime.InteropServices.RuntimeInformation.OSArchitecture.ToString() == "Arm64"
                            ? HostArchitecture.Arm64 : HostArchitecture.X64));
        }

        // ---- build step ------------------------------------------------------------------------

        [Test]
        public void BuildStepCopiesTheConfiguredModelToStreamingAssetsUnderItsOwnName()
        {
            var project = TestPaths.NewTempDirectory("project");
            var fp16 = Touch(project, "Packages", "com.mocap.imu", "Runtime", "Models", "mocap_pose_fp16.onnx");
            var copy = PlayerPaths.ModelCopyForBuild(RunningContext.Editor(HostOs.Linux, project),
                                                     "Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp16.onnx");
            Assert.That(copy.Source, Is.EqualTo(fp16));
            Assert.That(copy.ProjectRelativeTarget, Is.EqualTo("Assets/StreamingAssets/com.mocap.imu/mocap_pose_fp16.onnx"));
            Assert.That(copy.AbsoluteTarget,
                        Is.EqualTo(Path.Combine(project, "Assets", "StreamingAssets", "com.mocap.imu", "mocap_pose_fp16.onnx")));
            Assert.That(PlayerPaths.ModelTargetInProject(null), Is.EqualTo("Assets/StreamingAssets/com.mocap.imu/" + ModelName));
        }

        [Test]
        public void WhatTheBuildStepCopiesIsWhatEveryPlayerFinds()
        {
            // Unity copies Assets/StreamingAssets verbatim into each player's StreamingAssets folder.
            var project = TestPaths.NewTempDirectory("project");
            Touch(project, "Packages", "com.mocap.imu", "Runtime", "Models", ModelName);
            var copy = PlayerPaths.ModelCopyForBuild(RunningContext.Editor(HostOs.Windows, project), null);
            const string streamingPrefix = "Assets/StreamingAssets/";
            StringAssert.StartsWith(streamingPrefix, copy.ProjectRelativeTarget);
            var insideStreaming = copy.ProjectRelativeTarget.Substring(streamingPrefix.Length).Split('/');
            foreach (HostOs os in Enum.GetValues(typeof(HostOs)))
            {
                var build = TestPaths.NewTempDirectory("build");
                var player = RunningContext.Player(os, PlayerDataFolder(os, build));
                var shipped = Touch(player.StreamingAssetsPath, insideStreaming);
                Assert.That(PlayerPaths.FindModel(player, null).Path, Is.EqualTo(shipped), os.ToString());
            }
        }

        [Test]
        public void BuildStepRefusesAMissingModelAndAPlayerContext()
        {
            var project = TestPaths.NewTempDirectory("project");
            var e = Assert.Throws<MocapException>(() => PlayerPaths.ModelCopyForBuild(RunningContext.Editor(HostOs.Linux, project), null));
            StringAssert.Contains(Path.Combine(project, "Packages", "com.mocap.imu", "Runtime", "Models", ModelName), e.Message);
            Assert.Throws<ArgumentException>(() => PlayerPaths.ModelCopyForBuild(RunningContext.Player(HostOs.Linux, project), null));
            Assert.Throws<ArgumentException>(() => PlayerPaths.ModelFileName("Packages/com.mocap.imu/Runtime/Models/"));
        }

        [Test]
        public void ContextsWithoutTheirPathsAreRefusedClearly()
        {
            var e = Assert.Throws<ArgumentException>(() => PlayerPaths.FindModel(new RunningContext { IsEditor = true }, null));
            StringAssert.Contains("project root", e.Message);
            e = Assert.Throws<ArgumentException>(() => PlayerPaths.FindModel(new RunningContext { IsEditor = false }, null));
            StringAssert.Contains("streamingAssetsPath", e.Message);
            Assert.Throws<ArgumentNullException>(() => PlayerPaths.FindModel(null, null));
        }

        // ---- serial ports ------------------------------------------------------------------------

        [Test]
        public void DefaultSerialPortPerOs()
        {
            Assert.That(SerialPortDefaults.DefaultPort(HostOs.Windows), Is.EqualTo("COM3"));
            Assert.That(SerialPortDefaults.DefaultPort(HostOs.Linux), Is.EqualTo("/dev/ttyUSB0"));
            Assert.That(SerialPortDefaults.DefaultPort(HostOs.MacOS), Is.EqualTo("/dev/cu.usbserial-0001"));
            foreach (HostOs os in Enum.GetValues(typeof(HostOs)))
                Assert.That(SerialPortDefaults.LooksLikeReceiver(os, SerialPortDefaults.DefaultPort(os)), Is.True, os.ToString());
        }

        [Test]
        public void PickPrefersUsbSerialBridgesAndIgnoresOtherDevices()
        {
            Assert.That(SerialPortDefaults.Pick(HostOs.Linux, new[] { "tty0", "ttyS0", "ttyACM0", "ttyUSB3", "ttyUSB1", "null" }),
                        Is.EqualTo("/dev/ttyUSB1"));
            Assert.That(SerialPortDefaults.Pick(HostOs.Linux, new[] { "/dev/ttyS0", "/dev/ttyACM2" }), Is.EqualTo("/dev/ttyACM2"));
            Assert.That(SerialPortDefaults.Pick(HostOs.MacOS,
                            new[] { "cu.Bluetooth-Incoming-Port", "tty.SLAB_USBtoUART", "cu.usbmodem14101", "cu.SLAB_USBtoUART" }),
                        Is.EqualTo("/dev/cu.SLAB_USBtoUART"), "cu.*, not tty.*, and a CP210x before a CDC modem");
            Assert.That(SerialPortDefaults.Pick(HostOs.MacOS, new[] { "/dev/cu.wchusbserial1410" }), Is.EqualTo("/dev/cu.wchusbserial1410"));
            Assert.That(SerialPortDefaults.Pick(HostOs.Windows, new[] { "COM1", "COM12", "COM4" }), Is.EqualTo("COM4"));
            Assert.That(SerialPortDefaults.Pick(HostOs.Windows, new[] { "COM1" }), Is.EqualTo("COM3"), "nothing but COM1: the default");
            Assert.That(SerialPortDefaults.Pick(HostOs.Linux, null), Is.EqualTo("/dev/ttyUSB0"));
        }

        [Test]
        public void PickDoesNotDependOnTheListingOrder()
        {
            var ports = new List<string> { "ttyUSB10", "ttyUSB2", "ttyACM0", "ttyUSB9" };
            var first = SerialPortDefaults.Pick(HostOs.Linux, ports);
            ports.Reverse();
            Assert.That(SerialPortDefaults.Pick(HostOs.Linux, ports), Is.EqualTo(first));
            Assert.That(first, Is.EqualTo("/dev/ttyUSB2"));
        }

        [Test]
        public void ListDevicesReadsAFolderLikeDev()
        {
            var dev = TestPaths.NewTempDirectory("dev");
            foreach (var name in new[] { "ttyS0", "ttyUSB0", "ttyACM1" }) Touch(dev, name);
            var names = SerialPortDefaults.ListDevices(dev);
            Assert.That(names, Is.EquivalentTo(new[] { "ttyS0", "ttyUSB0", "ttyACM1" }));
            Assert.That(SerialPortDefaults.Pick(HostOs.Linux, names), Is.EqualTo("/dev/ttyUSB0"));
            var e = Assert.Throws<MocapException>(() => SerialPortDefaults.ListDevices(Path.Combine(dev, "missing")));
            StringAssert.Contains(Path.Combine(dev, "missing"), e.Message);
        }
    }
}
