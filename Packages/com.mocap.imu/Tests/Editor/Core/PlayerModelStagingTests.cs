// PlayerModelStaging on a real project folder: the build step copies the configured models into
// Assets/StreamingAssets/com.mocap.imu, the post-build step removes exactly what it created, and a
// failed build's leftovers go at the next build.

using System.IO;
using System.Linq;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    public sealed class PlayerModelStagingTests
    {
        static string NewProject(out string modelsFolder)
        {
            var project = TestPaths.NewTempDirectory("project");
            Directory.CreateDirectory(Path.Combine(project, "Assets"));
            modelsFolder = Path.Combine(project, "Packages", "com.mocap.imu", "Runtime", "Models");
            Directory.CreateDirectory(modelsFolder);
            File.WriteAllBytes(Path.Combine(modelsFolder, "mocap_pose_int8.onnx"), new byte[] { 1, 2, 3, 4 });
            File.WriteAllBytes(Path.Combine(modelsFolder, "mocap_pose_fp16.onnx"), new byte[] { 5, 6 });
            return project;
        }

        [Test]
        public void StagingCopiesTheModelsAndUnstagingRemovesOnlyWhatItCreated()
        {
            var project = NewProject(out _);
            var editor = RunningContext.Editor(HostOs.Linux, project);
            var plan = PlayerModelStaging.Plan(editor, new[] { null, "Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp16.onnx" });
            Assert.That(plan.Select(c => c.ProjectRelativeTarget),
                        Is.EqualTo(new[] { "Assets/StreamingAssets/com.mocap.imu/mocap_pose_int8.onnx",
                                           "Assets/StreamingAssets/com.mocap.imu/mocap_pose_fp16.onnx" }),
                        "an empty model path is the default model, which the player then needs");

            var created = PlayerModelStaging.Stage(project, plan);
            var target = Path.Combine(project, "Assets", "StreamingAssets", "com.mocap.imu", "mocap_pose_fp16.onnx");
            Assert.That(File.ReadAllBytes(target), Is.EqualTo(new byte[] { 5, 6 }));
            Assert.That(File.ReadAllBytes(Path.Combine(Path.GetDirectoryName(target), "mocap_pose_int8.onnx")), Is.EqualTo(new byte[] { 1, 2, 3, 4 }));
            Assert.That(created, Is.EqualTo(new[]
            {
                "Assets/StreamingAssets/", "Assets/StreamingAssets/com.mocap.imu/", "Assets/StreamingAssets/com.mocap.imu/mocap_pose_int8.onnx",
                "Assets/StreamingAssets/com.mocap.imu/mocap_pose_fp16.onnx",
            }));
            // A player built now finds the model where the build put it.
            var player = RunningContext.Player(HostOs.Linux, Path.Combine(project, "Assets"));
            Assert.That(PlayerPaths.FindModel(player, "Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp16.onnx").Path, Is.EqualTo(target));

            // The editor imports what appeared: .meta files that must go too.
            File.WriteAllText(target + ".meta", "m");
            File.WriteAllText(Path.Combine(project, "Assets", "StreamingAssets", "com.mocap.imu.meta"), "m");
            PlayerModelStaging.Unstage(project);
            Assert.That(Directory.Exists(Path.Combine(project, "Assets", "StreamingAssets")), Is.False);
            Assert.That(File.Exists(Path.Combine(project, "Assets", "StreamingAssets.meta")), Is.False);
            Assert.That(Directory.Exists(Path.Combine(project, "Assets")), Is.True);
            Assert.That(File.Exists(Path.Combine(project, PlayerModelStaging.StagedListPath)), Is.False);
        }

        [Test]
        public void TheProjectsOwnStreamingAssetsStay()
        {
            var project = NewProject(out _);
            var streaming = Path.Combine(project, "Assets", "StreamingAssets");
            Directory.CreateDirectory(streaming);
            var own = Path.Combine(streaming, "config.json");
            File.WriteAllText(own, "{}");
            PlayerModelStaging.Stage(project, PlayerModelStaging.Plan(RunningContext.Editor(HostOs.Windows, project), null));
            Assert.That(File.Exists(Path.Combine(streaming, "com.mocap.imu", "mocap_pose_int8.onnx")), Is.True);
            var removed = PlayerModelStaging.Unstage(project);
            Assert.That(removed, Is.EqualTo(new[] { "Assets/StreamingAssets/com.mocap.imu/mocap_pose_int8.onnx", "Assets/StreamingAssets/com.mocap.imu/" }));
            Assert.That(File.ReadAllText(own), Is.EqualTo("{}"));
            Assert.That(Directory.Exists(Path.Combine(streaming, "com.mocap.imu")), Is.False);
        }

        [Test]
        public void AModelAlreadyInPlaceIsKeptAndADifferentOneIsRefused()
        {
            var project = NewProject(out var models);
            var folder = Path.Combine(project, "Assets", "StreamingAssets", "com.mocap.imu");
            Directory.CreateDirectory(folder);
            var placed = Path.Combine(folder, "mocap_pose_int8.onnx");
            File.Copy(Path.Combine(models, "mocap_pose_int8.onnx"), placed);
            var plan = PlayerModelStaging.Plan(RunningContext.Editor(HostOs.MacOS, project), null);
            Assert.That(PlayerModelStaging.Stage(project, plan), Is.Empty);
            PlayerModelStaging.Unstage(project);
            Assert.That(File.Exists(placed), Is.True, "a file the step did not create is never removed");

            File.WriteAllBytes(placed, new byte[] { 9, 9, 9, 9 });
            var e = Assert.Throws<MocapException>(() => PlayerModelStaging.Stage(project, plan));
            Assert.That(e.Status, Is.EqualTo(MocapStatus.InvalidArgument));
            StringAssert.Contains("Assets/StreamingAssets/com.mocap.imu/mocap_pose_int8.onnx", e.Message);
            Assert.That(File.ReadAllBytes(placed), Is.EqualTo(new byte[] { 9, 9, 9, 9 }));
        }

        [Test]
        public void AFailedBuildsLeftoversGoAtTheNextStaging()
        {
            var project = NewProject(out _);
            var editor = RunningContext.Editor(HostOs.Linux, project);
            PlayerModelStaging.Stage(project, PlayerModelStaging.Plan(editor, new[] { "Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp16.onnx" }));
            // No post-build call (the build failed); the next build ships only the default model.
            PlayerModelStaging.Stage(project, PlayerModelStaging.Plan(editor, null));
            var folder = Path.Combine(project, "Assets", "StreamingAssets", "com.mocap.imu");
            Assert.That(Directory.GetFiles(folder).Select(Path.GetFileName), Is.EqualTo(new[] { "mocap_pose_int8.onnx" }));
        }

        [Test]
        public void PlanRefusesMissingModelsAndNameClashes()
        {
            var project = NewProject(out _);
            var editor = RunningContext.Editor(HostOs.Linux, project);
            var e = Assert.Throws<MocapException>(() => PlayerModelStaging.Plan(editor, new[] { "Assets/Models/none.onnx" }));
            Assert.That(e.Status, Is.EqualTo(MocapStatus.NotFound));
            StringAssert.Contains(Path.Combine(project, "Assets", "Models", "none.onnx"), e.Message);

            var other = Path.Combine(project, "Assets", "Other");
            Directory.CreateDirectory(other);
            File.WriteAllBytes(Path.Combine(other, "mocap_pose_int8.onnx"), new byte[] { 7 });
            e = Assert.Throws<MocapException>(() => PlayerModelStaging.Plan(editor, new[] { null, "Assets/Other/mocap_pose_int8.onnx" }));
            Assert.That(e.Status, Is.EqualTo(MocapStatus.InvalidArgument));
            StringAssert.Contains("share the file name mocap_pose_int8.onnx", e.Message);
            Assert.That(PlayerModelStaging.Plan(editor, new[] { "", PlayerPaths.DefaultModelPath }).Count, Is.EqualTo(1),
                        "the default given twice (empty and spelled out) is one copy");
        }
    }
}
