using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>
    /// Owns one native mocap_solver and keeps what it reads alive: it holds a reference on its
    /// model's handle and on the handle of every session added as a character, and gives them
    /// back only after mocap_solver_close has stopped the inference thread. So the C API's order
    /// (solver first, then its sessions, then the model) holds even when the managed objects are
    /// disposed in another order or finalized together: disposing a session or the model early
    /// only defers its native close until the solver is gone.
    /// </summary>
    public sealed class SolverHandle : SafeHandle
    {
        // Written before Start on the owning thread; read by ReleaseHandle after every other
        // use of the handle has ended (SafeHandle's reference count guarantees that).
        readonly List<SafeHandle> _dependencies = new List<SafeHandle>(4);

        internal SolverHandle() : base(IntPtr.Zero, ownsHandle: true)
        {
        }

        /// <inheritdoc/>
        public override bool IsInvalid => handle == IntPtr.Zero;

        /// <summary>
        /// Take a reference on a handle the native solver will use. Call before handing its
        /// pointer to the engine; the reference is released after the solver closes.
        /// </summary>
        internal void AddDependency(SafeHandle dependency)
        {
            bool added = false;
            dependency.DangerousAddRef(ref added);
            if (added) _dependencies.Add(dependency);
        }

        /// <summary>Give back the reference of the last <see cref="AddDependency"/> (the engine refused it).</summary>
        internal void RemoveLastDependency()
        {
            int last = _dependencies.Count - 1;
            _dependencies[last].DangerousRelease();
            _dependencies.RemoveAt(last);
        }

        /// <summary>
        /// Called once mocap_solver_close has returned (on the thread that released the handle:
        /// Dispose's, the last solver call's, or the finalizer's), before the dependencies go.
        /// </summary>
        internal Action Closed;

        /// <summary>Adopt the pointer mocap_solver_open returned (once, right after the open).</summary>
        internal void Adopt(IntPtr solver) => SetHandle(solver);

        /// <inheritdoc/>
        protected override bool ReleaseHandle()
        {
            // Stops and joins the inference thread: after this nothing reads the sessions or model.
            NativeSolverMethods.mocap_solver_close(handle);
            Closed?.Invoke();
            Closed = null;
            // Sessions before the model, mirroring the C API's close order.
            for (int i = _dependencies.Count - 1; i >= 0; i--) _dependencies[i].DangerousRelease();
            _dependencies.Clear();
            return true;
        }
    }
}
