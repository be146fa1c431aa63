using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// A minimal stage for driven avatars, for scenes built from code (the samples) or empty
    /// scenes: a floor with a collider (a <see cref="PhysicsCharacter"/> stands on it), a
    /// directional light when the scene has none, and a camera framing an avatar.
    /// </summary>
    [DisallowMultipleComponent]
    [AddComponentMenu("Mocap IMU/Mocap Stage")]
    public sealed class MocapStage : MonoBehaviour
    {
        // Unity's Plane primitive is 10 m on a side at scale 1.
        const float PlaneSize = 10f;

        [Tooltip("Side of the square floor, metres.")]
        [Min(0.1f)] public float floorSize = 40f;

        [Tooltip("Camera position relative to the framed avatar's root, metres (+z: in front of an avatar facing -z).")]
        public Vector3 cameraOffset = new Vector3(0f, 1.2f, 3.5f);

        [Tooltip("Height above the framed avatar's root the camera looks at, metres.")]
        public float lookAtHeight = 0.9f;

        /// <summary>The floor this stage built (null before <see cref="Build"/>).</summary>
        public GameObject Floor { get; private set; }

        /// <summary>
        /// Build the floor (once) as a child of this object, and a directional light unless the
        /// scene already has a light.
        /// </summary>
        public void Build()
        {
            if (Floor == null)
            {
                Floor = GameObject.CreatePrimitive(PrimitiveType.Plane); // has a MeshCollider
                Floor.name = "Floor";
                Floor.transform.SetParent(transform, false);
                float scale = floorSize / PlaneSize;
                Floor.transform.localScale = new Vector3(scale, 1f, scale);
            }
            if (FindAnyObjectByType<Light>() == null)
            {
                var light = new GameObject("Light").AddComponent<Light>();
                light.type = LightType.Directional;
                light.transform.SetParent(transform, false);
                light.transform.rotation = Quaternion.Euler(50f, -30f, 0f);
            }
        }

        /// <summary>
        /// Place the main camera (created when the scene has none) at <see cref="cameraOffset"/>
        /// from the target, looking at it; returns the camera.
        /// </summary>
        public Camera Frame(Transform target)
        {
            if (target == null) throw new System.ArgumentNullException(nameof(target), "the stage needs an avatar to frame");
            var camera = Camera.main;
            if (camera == null)
            {
                camera = new GameObject("Main Camera").AddComponent<Camera>();
                camera.tag = "MainCamera";
            }
            camera.transform.position = target.position + cameraOffset;
            camera.transform.LookAt(target.position + Vector3.up * lookAtHeight);
            return camera;
        }
    }
}
