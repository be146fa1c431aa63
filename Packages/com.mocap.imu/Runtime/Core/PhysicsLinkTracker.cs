// When a physics character's links must be built, rebuilt or dropped, and when their collision
// ignores must be applied again. Unity forgets a collider's IgnoreCollision pairs when the collider
// is deactivated, and a driver that reads a new avatar makes a new rig whose bones the old links
// no longer mirror.

namespace Mocap.Imu
{
    /// <summary>What a physics character does with its links this frame.</summary>
    public enum PhysicsLinkAction
    {
        /// <summary>The links mirror the current rig: keep them.</summary>
        Keep,
        /// <summary>No links yet and a rig to mirror: build them.</summary>
        Build,
        /// <summary>The driver read its avatar again (a new rig): destroy the links and build new ones.</summary>
        Rebuild,
        /// <summary>No rig any more, or one of its bones was destroyed: destroy the links.</summary>
        Clear,
    }

    /// <summary>
    /// The physics character's link state: which rig the links were built for and whether the
    /// links' collision ignores are in force. Rigs are compared by reference (the driver makes a
    /// new one whenever it reads the avatar again).
    /// </summary>
    public sealed class PhysicsLinkTracker
    {
        object _builtFor;
        bool _ignoresApplied;

        /// <summary>The rig the current links mirror (null when there are none).</summary>
        public object BuiltFor => _builtFor;

        /// <summary>Links exist and their collision ignores must be applied (after a build or a re-enable).</summary>
        public bool NeedsIgnores => _builtFor != null && !_ignoresApplied;

        /// <summary>The action for the driver's current rig (null: none) and whether any of its bones is gone.</summary>
        public PhysicsLinkAction Check(object currentRig, bool anyBoneDestroyed)
        {
            if (currentRig == null || anyBoneDestroyed)
                return _builtFor != null ? PhysicsLinkAction.Clear : PhysicsLinkAction.Keep;
            if (_builtFor == null) return PhysicsLinkAction.Build;
            return ReferenceEquals(currentRig, _builtFor) ? PhysicsLinkAction.Keep : PhysicsLinkAction.Rebuild;
        }

        /// <summary>Links were built for <paramref name="rig"/>; their ignores are not applied yet.</summary>
        public void Built(object rig)
        {
            _builtFor = rig;
            _ignoresApplied = false;
        }

        /// <summary>The links were destroyed.</summary>
        public void Cleared()
        {
            _builtFor = null;
            _ignoresApplied = false;
        }

        /// <summary>The links' colliders were deactivated: Unity dropped their ignore pairs.</summary>
        public void Deactivated() => _ignoresApplied = false;

        /// <summary>Every pair of links now ignores each other.</summary>
        public void IgnoresApplied() => _ignoresApplied = _builtFor != null;
    }
}
