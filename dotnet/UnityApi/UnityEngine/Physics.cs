// Declarations only (see ../README.md): colliders, rigid bodies, articulations.
using System;

namespace UnityEngine
{
    public enum ForceMode { Force = 0, Acceleration = 5, Impulse = 1, VelocityChange = 2 }

    public partial class Physics
    {
        public static Vector3 gravity { get => throw null; set => throw null; }
        public static void IgnoreCollision(Collider collider1, Collider collider2) => throw null;
        public static void IgnoreCollision(Collider collider1, Collider collider2, bool ignore) => throw null;
        public static bool GetIgnoreCollision(Collider collider1, Collider collider2) => throw null;
        public static bool Raycast(Vector3 origin, Vector3 direction, out RaycastHit hitInfo, float maxDistance) => throw null;
        public static void SyncTransforms() => throw null;
        public static bool autoSyncTransforms { get => throw null; set => throw null; }
    }

    public partial struct RaycastHit
    {
        public Vector3 point { get => throw null; set => throw null; }
        public Vector3 normal { get => throw null; set => throw null; }
        public float distance { get => throw null; set => throw null; }
        public Collider collider => throw null;
    }

    public partial class Collider : Component
    {
        public bool enabled { get => throw null; set => throw null; }
        public bool isTrigger { get => throw null; set => throw null; }
        public Bounds bounds => throw null;
        public Rigidbody attachedRigidbody => throw null;
        public ArticulationBody attachedArticulationBody => throw null;
    }

    public partial class SphereCollider : Collider
    {
        public Vector3 center { get => throw null; set => throw null; }
        public float radius { get => throw null; set => throw null; }
    }

    public partial class CapsuleCollider : Collider
    {
        public Vector3 center { get => throw null; set => throw null; }
        public float radius { get => throw null; set => throw null; }
        public float height { get => throw null; set => throw null; }
        public int direction { get => throw null; set => throw null; }
    }

    public partial class BoxCollider : Collider
    {
        public Vector3 center { get => throw null; set => throw null; }
        public Vector3 size { get => throw null; set => throw null; }
    }

    public partial class MeshCollider : Collider
    {
        public bool convex { get => throw null; set => throw null; }
    }

    public partial class Rigidbody : Component
    {
#if UNITY_6000_0_OR_NEWER
        public Vector3 linearVelocity { get => throw null; set => throw null; }
        [Obsolete("velocity has been deprecated. Use linearVelocity instead. (UnityUpgradable) -> linearVelocity")]
        public Vector3 velocity { get => throw null; set => throw null; }
        public float linearDamping { get => throw null; set => throw null; }
        [Obsolete("drag has been deprecated. Use linearDamping instead. (UnityUpgradable) -> linearDamping")]
        public float drag { get => throw null; set => throw null; }
#else
        public Vector3 velocity { get => throw null; set => throw null; }
        public float drag { get => throw null; set => throw null; }
#endif
        public Vector3 angularVelocity { get => throw null; set => throw null; }
        public float mass { get => throw null; set => throw null; }
        public bool isKinematic { get => throw null; set => throw null; }
        public bool useGravity { get => throw null; set => throw null; }
        public Vector3 position { get => throw null; set => throw null; }
        public Quaternion rotation { get => throw null; set => throw null; }
        public void AddForce(Vector3 force) => throw null;
        public void AddForce(Vector3 force, ForceMode mode) => throw null;
        public void AddTorque(Vector3 torque) => throw null;
        public void AddTorque(Vector3 torque, ForceMode mode) => throw null;
        public void MovePosition(Vector3 position) => throw null;
        public void MoveRotation(Quaternion rot) => throw null;
    }

    public enum ArticulationJointType { FixedJoint = 0, PrismaticJoint = 1, RevoluteJoint = 2, SphericalJoint = 3 }
    public enum ArticulationDofLock { LockedMotion = 0, LimitedMotion = 1, FreeMotion = 2 }
    public enum ArticulationDriveType { Force = 0, Acceleration = 1, Target = 2, Velocity = 3 }

    public partial struct ArticulationDrive
    {
        public float lowerLimit;
        public float upperLimit;
        public float stiffness;
        public float damping;
        public float forceLimit;
        public float target;
        public float targetVelocity;
        public ArticulationDriveType driveType;
    }

    public partial struct ArticulationReducedSpace
    {
        public ArticulationReducedSpace(float a) => throw null;
        public ArticulationReducedSpace(float a, float b, float c) => throw null;
        public float this[int i] { get => throw null; set => throw null; }
        public int dofCount;
    }

    public partial class ArticulationBody : Behaviour
    {
        public ArticulationJointType jointType { get => throw null; set => throw null; }
        public Vector3 anchorPosition { get => throw null; set => throw null; }
        public Vector3 parentAnchorPosition { get => throw null; set => throw null; }
        public Quaternion anchorRotation { get => throw null; set => throw null; }
        public Quaternion parentAnchorRotation { get => throw null; set => throw null; }
        public bool isRoot => throw null;
        public bool matchAnchors { get => throw null; set => throw null; }
        public ArticulationDofLock linearLockX { get => throw null; set => throw null; }
        public ArticulationDofLock linearLockY { get => throw null; set => throw null; }
        public ArticulationDofLock linearLockZ { get => throw null; set => throw null; }
        public ArticulationDofLock swingYLock { get => throw null; set => throw null; }
        public ArticulationDofLock swingZLock { get => throw null; set => throw null; }
        public ArticulationDofLock twistLock { get => throw null; set => throw null; }
        public ArticulationDrive xDrive { get => throw null; set => throw null; }
        public ArticulationDrive yDrive { get => throw null; set => throw null; }
        public ArticulationDrive zDrive { get => throw null; set => throw null; }
        public bool immovable { get => throw null; set => throw null; }
        public bool useGravity { get => throw null; set => throw null; }
        public float linearDamping { get => throw null; set => throw null; }
        public float angularDamping { get => throw null; set => throw null; }
        public float jointFriction { get => throw null; set => throw null; }
        public float mass { get => throw null; set => throw null; }
        public Vector3 centerOfMass { get => throw null; set => throw null; }
        public Vector3 worldCenterOfMass => throw null;
        public Vector3 inertiaTensor { get => throw null; set => throw null; }
#if UNITY_6000_0_OR_NEWER
        public Vector3 linearVelocity { get => throw null; set => throw null; }
        [Obsolete("velocity has been deprecated. Use linearVelocity instead. (UnityUpgradable) -> linearVelocity")]
        public Vector3 velocity { get => throw null; set => throw null; }
#else
        public Vector3 velocity { get => throw null; set => throw null; }
#endif
        public Vector3 angularVelocity { get => throw null; set => throw null; }
        public ArticulationReducedSpace jointPosition { get => throw null; set => throw null; }
        public ArticulationReducedSpace jointVelocity { get => throw null; set => throw null; }
        public int dofCount => throw null;
        public int index => throw null;
        public void AddForce(Vector3 force) => throw null;
        public void AddForce(Vector3 force, ForceMode mode) => throw null;
        public void AddTorque(Vector3 torque) => throw null;
        public void AddTorque(Vector3 torque, ForceMode mode) => throw null;
        public void TeleportRoot(Vector3 position, Quaternion rotation) => throw null;
        public void ResetCenterOfMass() => throw null;
        public void ResetInertiaTensor() => throw null;
        public void Sleep() => throw null;
        public void WakeUp() => throw null;
    }
}
