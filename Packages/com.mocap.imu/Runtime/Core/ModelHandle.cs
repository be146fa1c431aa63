using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>
    /// Owns one native mocap_model. A <see cref="SolverHandle"/> built on it holds a reference
    /// (SafeHandle.DangerousAddRef), so the model is freed only after every solver using it has
    /// closed, whatever order the managed objects are disposed or finalized in: the C API forbids
    /// closing a model while a solver uses it.
    /// </summary>
    public sealed class ModelHandle : SafeHandle
    {
        internal ModelHandle(IntPtr model) : base(IntPtr.Zero, ownsHandle: true)
        {
            SetHandle(model);
        }

        /// <inheritdoc/>
        public override bool IsInvalid => handle == IntPtr.Zero;

        /// <inheritdoc/>
        protected override bool ReleaseHandle()
        {
            NativeSolverMethods.mocap_model_close(handle);
            return true;
        }
    }
}
