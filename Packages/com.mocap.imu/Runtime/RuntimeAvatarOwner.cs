using UnityEngine;

namespace Mocap.Imu
{
    /// <summary>
    /// Destroys an Avatar built at run time (AvatarBuilder) together with the GameObject it was
    /// built for. An Avatar is an object of its own that outlives the GameObjects using it, so every
    /// avatar built and dropped (a sample restarted, a test's character) would otherwise stay in
    /// memory until the next scene unload.
    /// </summary>
    /// <remarks>
    /// Runs in edit mode too: editor scripts and EditMode tests build characters as well. A copy
    /// made with Instantiate shares the Avatar but does not own it (the reference is not serialized).
    /// </remarks>
    [ExecuteAlways]
    [DisallowMultipleComponent]
    [AddComponentMenu("")]
    public sealed class RuntimeAvatarOwner : MonoBehaviour
    {
        /// <summary>The Avatar destroyed with this GameObject (null: none).</summary>
        public Avatar Owned { get; internal set; }

        void OnDestroy()
        {
            if (Owned == null) return;
            if (Application.isPlaying) Destroy(Owned);
            else DestroyImmediate(Owned);
            Owned = null;
        }
    }
}
