// EditMode: the stage the samples build their scenes with (MocapStage): a floor of the asked size
// under the stage, a directional light only when the scene has none, a camera framing the avatar.

using System.Collections.Generic;
using NUnit.Framework;
using UnityEngine;

namespace Mocap.Imu.Tests
{
    public sealed class MocapStageTests
    {
        readonly List<GameObject> _created = new List<GameObject>();

        GameObject Track(GameObject go)
        {
            _created.Add(go);
            return go;
        }

        [TearDown]
        public void DestroyWhatTheTestBuilt()
        {
            foreach (var go in _created)
                if (go != null) Object.DestroyImmediate(go);
            _created.Clear();
        }

        [Test]
        public void BuildMakesOneFloorOfTheAskedSizeUnderTheStage()
        {
            var stage = Track(new GameObject("Stage")).AddComponent<MocapStage>();
            stage.floorSize = 25f;
            stage.Build();
            Assert.IsNotNull(stage.Floor);
            Assert.AreSame(stage.transform, stage.Floor.transform.parent);
            Assert.IsNotNull(stage.Floor.GetComponent<Collider>(), "a physics character needs the floor's collider");
            Assert.AreEqual(2.5f, stage.Floor.transform.localScale.x, 1e-6f); // Plane: 10 m at scale 1
            Assert.AreEqual(2.5f, stage.Floor.transform.localScale.z, 1e-6f);

            var first = stage.Floor;
            stage.Build();
            Assert.AreSame(first, stage.Floor, "a second Build must not add a second floor");
        }

        [Test]
        public void BuildAddsALightOnlyWhenTheSceneHasNone()
        {
            var existing = Object.FindAnyObjectByType<Light>();
            if (existing == null) existing = Track(new GameObject("Existing light")).AddComponent<Light>();
            var stage = Track(new GameObject("Stage")).AddComponent<MocapStage>();
            stage.Build();
            Assert.IsNull(stage.GetComponentInChildren<Light>(), "the scene had a light: the stage must not add one");
        }

        [Test]
        public void FrameLooksAtTheAvatarFromTheOffset()
        {
            var stage = Track(new GameObject("Stage")).AddComponent<MocapStage>();
            var avatar = Track(new GameObject("Avatar")).transform;
            avatar.position = new Vector3(2f, 0f, -1f);
            // The open scene's own camera, if any, is moved by Frame: put it back afterwards.
            var sceneCamera = Camera.main;
            Vector3 scenePosition = sceneCamera != null ? sceneCamera.transform.position : Vector3.zero;
            Quaternion sceneRotation = sceneCamera != null ? sceneCamera.transform.rotation : Quaternion.identity;
            var camera = stage.Frame(avatar);
            if (sceneCamera == null) Track(camera.gameObject);
            try
            {
                Assert.AreEqual(0f, Vector3.Distance(avatar.position + stage.cameraOffset, camera.transform.position), 1e-4f);
                var toTarget = (avatar.position + Vector3.up * stage.lookAtHeight - camera.transform.position).normalized;
                Assert.Greater(Vector3.Dot(camera.transform.forward, toTarget), 0.9999f);
                Assert.Throws<System.ArgumentNullException>(() => stage.Frame(null));
            }
            finally
            {
                if (sceneCamera != null) sceneCamera.transform.SetPositionAndRotation(scenePosition, sceneRotation);
            }
        }
    }
}
