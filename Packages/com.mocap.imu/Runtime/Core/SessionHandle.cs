using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>
    /// Owns one native mocap_session. Closing stops the engine's threads and frees the session.
    /// Passing the handle to P/Invoke takes a reference for the call, so the session cannot be
    /// closed under a running call (the C API requires that no call is in progress on close),
    /// and a leaked session is still closed by the finalizer.
    /// </summary>
    public sealed class SessionHandle : SafeHandle
    {
        // Constructed from the pointer mocap_session_open returned, not through the marshaller's
        // "out SafeHandle", so no reflection-created instance is needed (IL2CPP stripping).
        internal SessionHandle(IntPtr session) : base(IntPtr.Zero, ownsHandle: true)
        {
            SetHandle(session);
        }

        public override bool IsInvalid => handle == IntPtr.Zero;

        protected override bool ReleaseHandle()
        {
            NativeMethods.mocap_session_close(handle);
            return true;
        }
    }
}
