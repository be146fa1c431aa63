// P/Invoke declarations of the VMC sender (Native~/include/mocap_imu.h, "Streaming and export").
// The same rules as NativeMethods: blittable parameters only, paths and addresses as
// NUL-terminated UTF-8 byte pointers, Cdecl. The structs are mirrored in NativeExportStructs.cs
// (checked against mocap_struct_layout by NativeLayoutTests).

using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    internal static unsafe class NativeVmcMethods
    {
        const string Library = NativeMethods.Library;
        const CallingConvention Cdecl = CallingConvention.Cdecl;

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_vmc_options_defaults(NativeVmcOptions* options);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_vmc_open(byte* destination, NativeVmcOptions* options,
                                                          out IntPtr vmc);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_vmc_send_pose(VmcHandle vmc, NativeModelInfo* info,
                                                               MocapPose* pose);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_vmc_get_stats(VmcHandle vmc, NativeVmcStats* stats);

        // Takes the raw pointer: only VmcHandle.ReleaseHandle calls it.
        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern void mocap_vmc_close(IntPtr vmc);
    }

    /// <summary>
    /// Owns one native mocap_vmc (a send-only UDP socket). Passing it to P/Invoke takes a
    /// reference for the call, so it cannot be closed under a running send.
    /// </summary>
    public sealed class VmcHandle : SafeHandle
    {
        internal VmcHandle(IntPtr vmc) : base(IntPtr.Zero, ownsHandle: true)
        {
            SetHandle(vmc);
        }

        /// <inheritdoc/>
        public override bool IsInvalid => handle == IntPtr.Zero;

        /// <inheritdoc/>
        protected override bool ReleaseHandle()
        {
            NativeVmcMethods.mocap_vmc_close(handle);
            return true;
        }
    }
}
