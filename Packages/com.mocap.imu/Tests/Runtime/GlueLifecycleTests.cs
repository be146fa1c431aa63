// PlayMode tests of the components' lifecycles on a procedural avatar (no engine, no sensors):
// the physics character's links after a disable/enable cycle and after its driver reads the
// avatar again, and the runtime-built Avatar's end with its character. The decisions behind them
// are tested outside Unity (Core's PhysicsLinkTracker); these check that the components apply them.

using System.Collections;
using System.Collections.Generic;
using NUnit.Framework;
using UnityEngine;
using UnityEngine.TestTools;

namespace Mocap.Imu.Tests
{
    public sealed class GlueLifecycleTests
    {
        readonly List<Object> _created = new List<Object>();

        [TearDown]
        public void DestroyScene()
        {
            foreach (var o in _created) if (o != null) Object.Destroy(o);
            _created.Clear();
        }

        PhysicsCharacter CreatePhysicsCharacter(out HumanoidPoseDriver driver)
        {
            var animator = ProceduralHumanoid.Create("Physics Avatar", Vector3.zero, visuals: false);
            _created.Add(animator.gameObject);
            driver = animator.gameObject.AddComponent<HumanoidPoseDriver>();
            Assert.AreEqual("", driver.Error);
            return animator.gameObject.AddComponent<PhysicsCharacter>();
        }

        static void AssertLinksIgnoreEachOther(PhysicsCharacter physics)
        {
            Assert.Greater(physics.LinkCount, 1, "the physics character built its links");
            for (int a = 0; a < physics.LinkCount; a++)
            {
                var first = physics.GetLink(a).GetComponent<Collider>();
                for (int b = a + 1; b < physics.LinkCount; b++)
                    Assert.IsTrue(Physics.GetIgnoreCollision(first, physics.GetLink(b).GetComponent<Collider>()),
                                  $"links {a} and {b} collide with each other");
            }
        }

        [UnityTest]
        public IEnumerator LinksStillIgnoreEachOtherAfterDisableAndEnable()
        {
            var physics = CreatePhysicsCharacter(out _);
            yield return null;
            AssertLinksIgnoreEachOther(physics);
            for (int cycle = 0; cycle < 2; cycle++)
            {
                physics.enabled = false;
                yield return new WaitForFixedUpdate();
                physics.enabled = true;
                yield return null;
                AssertLinksIgnoreEachOther(physics);
            }
        }

        [UnityTest]
        public IEnumerator LinksFollowARebuiltRig()
        {
            var physics = CreatePhysicsCharacter(out var driver);
            yield return null;
            var oldHips = physics.GetLink(0);
            Assert.IsNotNull(oldHips);
            driver.Rebuild();
            yield return null;
            yield return null;
            Assert.IsTrue(oldHips == null, "the links of the old rig are destroyed");
            Assert.AreEqual(driver.BoneCount, physics.LinkCount);
            Assert.IsTrue(physics.GetLink(0) != null, "new links were built for the new rig");
            AssertLinksIgnoreEachOther(physics);
        }

        [UnityTest]
        public IEnumerator TheRuntimeAvatarIsDestroyedWithItsCharacter()
        {
            var animator = ProceduralHumanoid.Create("Short-lived Avatar", Vector3.zero, visuals: false);
            var avatar = animator.avatar;
            Assert.IsTrue(avatar != null && avatar.isHuman);
            Object.Destroy(animator.gameObject);
            yield return null;
            Assert.IsTrue(avatar == null, "the Avatar built for the character outlived it");
        }
    }
}
