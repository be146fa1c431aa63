// PlayMode tests: the package's capture fixture (Fixtures/walk.cap, made by
// scripts/make_test_fixtures.sh) is played through MocapSessionComponent (engine + model) onto a
// procedural Humanoid avatar driven by HumanoidPoseDriver, and the avatar is checked every frame.
// The same bands are checked outside Unity on the same fixture by the core test
// UnityGlueCoreTests.TheCommittedFixtureDrivesTheProceduralAvatarWithinThePlayModeBands.

using System.Collections;
using System.Collections.Generic;
using System.IO;
using System.Text.RegularExpressions;
using NUnit.Framework;
using UnityEngine;
using UnityEngine.TestTools;

namespace Mocap.Imu.Tests
{
    public sealed class HumanoidPlaybackTests
    {
        const string Fixture = "Packages/com.mocap.imu/Tests/Runtime/Fixtures/walk.cap";
        readonly List<Object> _created = new List<Object>();

        [TearDown]
        public void DestroyScene()
        {
            foreach (var o in _created) if (o != null) Object.Destroy(o);
            _created.Clear();
        }

        MocapSessionComponent CreateSession(string capture, float speed)
        {
            var settings = ScriptableObject.CreateInstance<MocapSettings>();
            _created.Add(settings);
            var source = settings.characters[0];
            source.name = "Fixture";
            source.source = MocapSourceKind.Replay;
            source.captureFile = capture;
            source.playbackRealtime = true;
            source.playbackSpeed = speed;
            source.playbackCalibrationWindows = true;
            var go = new GameObject("Mocap Session");
            _created.Add(go);
            go.SetActive(false);
            var session = go.AddComponent<MocapSessionComponent>();
            session.settings = settings;
            go.SetActive(true);
            return session;
        }

        static IEnumerator WaitUntilOpen(MocapSessionComponent session)
        {
            float deadline = Time.realtimeSinceStartup + 60f;
            while (session.Status == MocapComponentStatus.Opening && Time.realtimeSinceStartup < deadline)
                yield return null;
        }

        [UnityTest]
        public IEnumerator TheFixtureDrivesTheAvatarWithinBands()
        {
            Assert.IsTrue(File.Exists(Path.GetFullPath(Fixture)), $"{Fixture} is missing (scripts/make_test_fixtures.sh)");
            var session = CreateSession(Fixture, speed: 3f);
            var animator = ProceduralHumanoid.Create("Test Avatar", Vector3.zero, visuals: false);
            _created.Add(animator.gameObject);
            Assert.IsTrue(animator.isHuman, "the procedural avatar is not humanoid");
            var driver = animator.gameObject.AddComponent<HumanoidPoseDriver>();
            driver.session = session;
            driver.rootMotion = Retarget.RootMotionMode.MoveHips;
            Assert.AreEqual("", driver.Error);
            Assert.AreEqual(22, driver.BoneCount, "every driven bone is present on the procedural avatar");

            var hips = animator.GetBoneTransform(HumanBodyBones.Hips);
            float restHips = hips.position.y;
            Assert.Greater(restHips, 0.7f);
            var feet = new[]
            {
                animator.GetBoneTransform(HumanBodyBones.LeftFoot), animator.GetBoneTransform(HumanBodyBones.RightFoot),
                animator.GetBoneTransform(HumanBodyBones.LeftToes), animator.GetBoneTransform(HumanBodyBones.RightToes),
            };

            yield return WaitUntilOpen(session);
            Assert.AreEqual(MocapComponentStatus.Running, session.Status, session.LastError);

            int frames = 0;
            Vector3 firstHips = default;
            Quaternion firstKnee = default;
            float moved = 0f, kneeTurned = 0f;
            var knee = animator.GetBoneTransform(HumanBodyBones.LeftLowerLeg);
            float deadline = Time.realtimeSinceStartup + 30f;
            while (session.Status == MocapComponentStatus.Running && Time.realtimeSinceStartup < deadline)
            {
                yield return null;
                if (!driver.HasTarget) continue;
                // Values written by the previous frame's LateUpdate.
                for (int i = 0; i < driver.BoneCount; i++)
                {
                    var q = driver.GetBone(i).localRotation;
                    Assert.IsFalse(float.IsNaN(q.x) || float.IsNaN(q.y) || float.IsNaN(q.z) || float.IsNaN(q.w) ||
                                   float.IsInfinity(q.x) || float.IsInfinity(q.w),
                                   $"frame {frames}: {driver.GetBone(i).name} rotation not finite");
                }
                float h = hips.position.y;
                Assert.That(h, Is.InRange(0.75f * restHips, 1.15f * restHips), $"frame {frames}: hips height");
                foreach (var f in feet)
                    Assert.GreaterOrEqual(f.position.y, -0.03f, $"frame {frames}: {f.name} below the floor");
                if (frames == 0)
                {
                    firstHips = hips.position;
                    firstKnee = knee.localRotation;
                }
                moved = Mathf.Max(moved, Vector3.Distance(firstHips, hips.position));
                kneeTurned = Mathf.Max(kneeTurned, Quaternion.Angle(firstKnee, knee.localRotation));
                frames++;
            }
            Assert.AreNotEqual(MocapComponentStatus.Failed, session.Status, session.LastError);
            Assert.Greater(frames, 20, "too few frames with a pose");
            Debug.Log($"[Mocap IMU test] {frames} frames, {session.GetPoseCount(0)} poses, hips moved {moved:F3} m, knee turned {kneeTurned:F2} deg");
            Assert.IsTrue(moved > 0.001f || kneeTurned > 0.5f, "the pose did not change over time");
        }

        [UnityTest]
        public IEnumerator AMissingCaptureFailsWithTheFileInTheError()
        {
            var session = CreateSession("Packages/com.mocap.imu/Tests/Runtime/Fixtures/no-such-capture.cap", 1f);
            // The component logs the failure as an error naming the file; any other error still fails the test.
            LogAssert.Expect(LogType.Error, new Regex(@"no-such-capture\.cap"));
            yield return WaitUntilOpen(session);
            Assert.AreEqual(MocapComponentStatus.Failed, session.Status);
            StringAssert.Contains("no-such-capture.cap", session.LastError);
            Assert.AreEqual(0, session.CharacterCount);
        }
    }
}
