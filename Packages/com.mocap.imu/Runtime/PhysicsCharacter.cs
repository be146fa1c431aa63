using System;
using System.Collections.Generic;
using Mocap.Imu.Retarget;
using UnityEngine;
using CoreBone = Mocap.Imu.Skeleton.HumanBone;

namespace Mocap.Imu
{
    /// <summary>
    /// Optional physics character for drift correction: an ArticulationBody chain mirroring the
    /// avatar's driven bones tracks the kinematic pose of a <see cref="HumanoidPoseDriver"/> with
    /// joint drives, stands on the floor under gravity (its feet collide with scene colliders, so
    /// they never sink), and is held upright and near the kinematic root by bounded PD forces.
    /// When <see cref="followPhysics"/> is on, the visible avatar shows the physics character.
    /// </summary>
    /// <remarks>
    /// The physics links are built at Start in a separate root object (not under the avatar), one
    /// per driven bone, with the bones' bind pose; the avatar must still be in its bind pose then.
    /// They are built again when the driver reads its avatar again (a new rig) and dropped when
    /// the rig or one of its bones is gone; their collision ignores are applied again on enable.
    /// A floor collider must exist in the scene. Joint targets are the rotation vector of each
    /// bone's rotation from its bind pose, in the bone's own frame (twist = X, swing = Y, Z).
    /// </remarks>
    [DefaultExecutionOrder(100)]
    [DisallowMultipleComponent]
    [RequireComponent(typeof(HumanoidPoseDriver))]
    [AddComponentMenu("Mocap IMU/Physics Character")]
    public sealed class PhysicsCharacter : MonoBehaviour
    {
        [Tooltip("The visible avatar shows the physics character instead of the kinematic pose.")]
        public bool followPhysics = true;

        [Header("Joint drives")]
        [Tooltip("Spring of every joint drive toward the kinematic pose (ArticulationDrive stiffness).")]
        [Min(0f)] public float stiffness = 2000f;
        [Tooltip("Damping of every joint drive (ArticulationDrive damping).")]
        [Min(0f)] public float damping = 80f;
        [Tooltip("Most force or torque one joint drive applies (ArticulationDrive forceLimit).")]
        [Min(0f)] public float forceLimit = 1000f;

        [Header("Root tracking (upright and drift)")]
        [Tooltip("Spring pulling the hips toward the kinematic hips, per kg (1/s^2).")]
        [Min(0f)] public float rootPositionGain = 200f;
        [Tooltip("Damping of the hips position spring, per kg (1/s).")]
        [Min(0f)] public float rootPositionDamping = 20f;
        [Tooltip("Spring turning the hips toward the kinematic hips rotation, per kg (1/s^2): keeps the body upright.")]
        [Min(0f)] public float rootRotationGain = 400f;
        [Tooltip("Damping of the hips rotation spring, per kg (1/s).")]
        [Min(0f)] public float rootRotationDamping = 30f;
        [Tooltip("Most force the root spring applies, as a multiple of body weight (1 = it can carry the whole body).")]
        [Min(0f)] public float maxRootForceBodyWeights = 0.8f;

        [Header("Body")]
        [Tooltip("Mass of the whole physics body, kg, shared among the bones like a human's.")]
        [Min(1f)] public float totalMass = 70f;
        [Tooltip("Collider radius of limbs as a fraction of the avatar's hips height.")]
        [Range(0.01f, 0.2f)] public float limbRadius = 0.06f;

        HumanoidPoseDriver _driver;
        GameObject _physicsRoot;
        ArticulationBody[] _links = Array.Empty<ArticulationBody>();
        Collider[] _colliders = Array.Empty<Collider>();
        readonly PhysicsLinkTracker _tracker = new PhysicsLinkTracker();
        bool _teleported;
        bool _drivesDirty = true;

        /// <summary>The physics link of rig bone <paramref name="index"/> (index as in the driver's rig).</summary>
        public ArticulationBody GetLink(int index) => _links[index];

        /// <summary>Number of links (0 before Start or when the avatar could not be read).</summary>
        public int LinkCount => _links.Length;

        void Start()
        {
            _driver = GetComponent<HumanoidPoseDriver>();
            FollowRig();
        }

        // After the driver's Update (execution order), before any LateUpdate writes a pose: a rig
        // the driver has just read again is still in its bind pose, which new links copy.
        void Update() => FollowRig();

        void FollowRig()
        {
            if (_driver == null) return;
            var rig = _driver.Rig;
            switch (_tracker.Check(rig, rig != null && AnyBoneDestroyed()))
            {
                case PhysicsLinkAction.Build:
                    Build();
                    break;
                case PhysicsLinkAction.Rebuild:
                    DestroyLinks();
                    Build();
                    break;
                case PhysicsLinkAction.Clear:
                    DestroyLinks();
                    break;
            }
        }

        bool AnyBoneDestroyed()
        {
            for (int i = 0; i < _driver.BoneCount; i++)
                if (_driver.GetBone(i) == null) return true;
            return false;
        }

        void DestroyLinks()
        {
            if (_physicsRoot != null)
            {
                // Destroy lands at the end of the frame: inactive until then, the old links touch nothing.
                _physicsRoot.SetActive(false);
                Destroy(_physicsRoot);
            }
            _physicsRoot = null;
            _links = Array.Empty<ArticulationBody>();
            _colliders = Array.Empty<Collider>();
            _tracker.Cleared();
            _teleported = false;
        }

        // Links touch their neighbours: only the world (floor, props) should collide with them.
        void ApplyIgnores()
        {
            for (int a = 0; a < _colliders.Length; a++)
                for (int b = a + 1; b < _colliders.Length; b++)
                    Physics.IgnoreCollision(_colliders[a], _colliders[b]);
            _tracker.IgnoresApplied();
        }

        void OnValidate() => _drivesDirty = true;

        void OnDestroy()
        {
            if (_physicsRoot != null) Destroy(_physicsRoot);
        }

        void OnDisable()
        {
            if (_driver != null) _driver.WriteTransforms = true;
            if (_physicsRoot != null) _physicsRoot.SetActive(false);
            // Unity forgets a deactivated collider's ignored pairs.
            _tracker.Deactivated();
        }

        void OnEnable()
        {
            if (_physicsRoot != null)
            {
                _physicsRoot.SetActive(true);
                _teleported = false;
                if (_tracker.NeedsIgnores) ApplyIgnores();
            }
        }

        static float MassShare(CoreBone b) => b switch
        {
            CoreBone.Hips => 11f,
            CoreBone.Spine or CoreBone.Chest or CoreBone.UpperChest => 8f,
            CoreBone.Neck => 1f,
            CoreBone.Head => 6f,
            CoreBone.LeftShoulder or CoreBone.RightShoulder => 1.5f,
            CoreBone.LeftUpperArm or CoreBone.RightUpperArm => 2.7f,
            CoreBone.LeftLowerArm or CoreBone.RightLowerArm => 1.6f,
            CoreBone.LeftHand or CoreBone.RightHand => 0.6f,
            CoreBone.LeftUpperLeg or CoreBone.RightUpperLeg => 10f,
            CoreBone.LeftLowerLeg or CoreBone.RightLowerLeg => 4.5f,
            CoreBone.LeftFoot or CoreBone.RightFoot => 1.2f,
            _ => 0.3f, // toes
        };

        void Build()
        {
            var rig = _driver.Rig;
            if (rig == null) return;
            int n = rig.Count;
            _physicsRoot = new GameObject(name + " (physics)");
            _links = new ArticulationBody[n];
            var colliders = new List<Collider>(n);
            float shareSum = 0f;
            for (int i = 0; i < n; i++) shareSum += MassShare(rig[i].Bone);
            float hipsHeight = Mathf.Max(0.1f, rig[0].RestPosition.Y * transform.lossyScale.y);

            for (int i = 0; i < n; i++)
            {
                var bone = _driver.GetBone(i);
                int p = rig.ParentIndex(i);
                var go = new GameObject("Physics " + rig[i].Bone);
                go.transform.SetParent(p < 0 ? _physicsRoot.transform : _links[p].transform, false);
                go.transform.SetPositionAndRotation(bone.position, bone.rotation);
                var body = go.AddComponent<ArticulationBody>();
                body.mass = totalMass * MassShare(rig[i].Bone) / shareSum;
                if (p >= 0)
                {
                    body.jointType = ArticulationJointType.SphericalJoint;
                    body.twistLock = ArticulationDofLock.FreeMotion;
                    body.swingYLock = ArticulationDofLock.FreeMotion;
                    body.swingZLock = ArticulationDofLock.FreeMotion;
                    body.matchAnchors = true;
                    body.anchorPosition = Vector3.zero;
                    body.anchorRotation = Quaternion.identity;
                }
                colliders.Add(AddCollider(go, rig, i, hipsHeight));
                _links[i] = body;
            }
            _colliders = colliders.ToArray();
            _tracker.Built(rig);
            ApplyIgnores();
            _drivesDirty = true;
            _teleported = false;
        }

        Collider AddCollider(GameObject go, HumanoidRig rig, int i, float hipsHeight)
        {
            // Capsule toward the mean of the bone's children; a sphere for end bones.
            Vector3 sum = Vector3.zero;
            int children = 0;
            for (int c = 0; c < rig.Count; c++)
                if (rig.ParentIndex(c) == i) { sum += _driver.GetBone(c).position; children++; }
            float radius = limbRadius * hipsHeight;
            var bone = rig[i].Bone;
            if (bone == CoreBone.Head) radius *= 1.6f;
            if (bone == CoreBone.Hips || bone == CoreBone.Spine || bone == CoreBone.Chest || bone == CoreBone.UpperChest) radius *= 1.8f;
            if (children == 0)
            {
                var sphere = go.AddComponent<SphereCollider>();
                sphere.radius = radius;
                return sphere;
            }
            Vector3 end = go.transform.InverseTransformPoint(sum / children);
            float length = end.magnitude;
            var capsule = go.AddComponent<CapsuleCollider>();
            capsule.center = end * 0.5f;
            capsule.radius = Mathf.Min(radius, length * 0.5f);
            capsule.height = length + 2f * capsule.radius;
            // Capsule direction: the local axis closest to the bone.
            Vector3 a = new Vector3(Mathf.Abs(end.x), Mathf.Abs(end.y), Mathf.Abs(end.z));
            capsule.direction = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
            return capsule;
        }

        void ApplyGains()
        {
            for (int i = 1; i < _links.Length; i++)
            {
                var body = _links[i];
                body.xDrive = WithGains(body.xDrive);
                body.yDrive = WithGains(body.yDrive);
                body.zDrive = WithGains(body.zDrive);
            }
            _drivesDirty = false;
        }

        ArticulationDrive WithGains(ArticulationDrive d)
        {
            d.stiffness = stiffness;
            d.damping = damping;
            d.forceLimit = forceLimit;
            return d;
        }

        void FixedUpdate()
        {
            if (_links.Length == 0 || _driver == null) return;
            if (!_driver.HasTarget)
            {
                // Lost the target (a new avatar or model): place the body again once one returns.
                _teleported = false;
                return;
            }
            if (_drivesDirty) ApplyGains();
            var root = _links[0];
            if (!_teleported)
            {
                root.TeleportRoot(_driver.TargetHipsWorldPosition, _driver.TargetHipsWorldRotation);
                _teleported = true;
            }

            // Joints: rotation from the bind pose in the bone's frame -> rotation vector targets (degrees).
            for (int i = 1; i < _links.Length; i++)
            {
                var bind = _driver.GetBindLocalRotation(i);
                var relative = Quaternion.Inverse(bind) * _driver.GetTargetLocalRotation(i);
                var target = DriveTargets.RotationVectorDegrees(relative.ToCore());
                var body = _links[i];
                var x = body.xDrive; x.target = target.X; body.xDrive = x;
                var y = body.yDrive; y.target = target.Y; body.yDrive = y;
                var z = body.zDrive; z.target = target.Z; body.zDrive = z;
            }

            // Root: bounded PD force toward the kinematic hips (drift and height) and torque toward its rotation (upright).
            float mass = totalMass;
#if UNITY_6000_0_OR_NEWER
            Vector3 rootVelocity = root.linearVelocity; // Unity 6 renamed velocity
#else
            Vector3 rootVelocity = root.velocity;
#endif
            Vector3 force = (rootPositionGain * (_driver.TargetHipsWorldPosition - root.transform.position)
                             - rootPositionDamping * rootVelocity) * mass;
            force = Vector3.ClampMagnitude(force, maxRootForceBodyWeights * mass * Physics.gravity.magnitude);
            root.AddForce(force);

            Quaternion error = _driver.TargetHipsWorldRotation * Quaternion.Inverse(root.transform.rotation);
            error.ToAngleAxis(out float angle, out Vector3 axis);
            if (angle > 180f) angle -= 360f;
            if (float.IsNaN(axis.x) || float.IsInfinity(axis.x)) axis = Vector3.zero;
            Vector3 torque = (rootRotationGain * angle * Mathf.Deg2Rad * axis - rootRotationDamping * root.angularVelocity) * mass;
            root.AddTorque(torque);
        }

        void LateUpdate()
        {
            if (_driver == null) return;
            bool follow = followPhysics && enabled && _links.Length > 0 && _driver.HasTarget && _teleported;
            _driver.WriteTransforms = !follow;
            if (!follow) return;
            // Links were created with the bones' world rotations, so world rotations map one to one.
            for (int i = 0; i < _links.Length; i++)
                _driver.GetBone(i).rotation = _links[i].transform.rotation;
            _driver.GetBone(0).position = _links[0].transform.position;
        }
    }
}
