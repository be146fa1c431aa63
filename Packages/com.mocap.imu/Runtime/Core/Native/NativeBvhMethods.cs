// P/Invoke declarations of the BVH writer (Native~/include/mocap_imu.h, "Streaming and export"):
// the same writer as `mocapctl replay --out`. Same rules as NativeMethods: blittable parameters
// only, paths as NUL-terminated UTF-8 byte pointers, Cdecl. The writer is a raw pointer rather
// than a SafeHandle because mocap_bvh_close reports the first write error, which a SafeHandle's
// ReleaseHandle could not return (BvhExporter owns it and closes it exactly once).

using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    internal static unsafe class NativeBvhMethods
    {
        const string Library = NativeMethods.Library;
        const CallingConvention Cdecl = CallingConvention.Cdecl;

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_bvh_options_defaults(NativeBvhOptions* options);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_bvh_open(byte* path, NativeModelInfo* info,
                                                          NativeBvhOptions* options, out IntPtr writer);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_bvh_append(IntPtr writer, MocapPose* pose);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern ulong mocap_bvh_frames(IntPtr writer);

        [DllImport(Library, CallingConvention = Cdecl)]
        internal static extern MocapStatus mocap_bvh_close(IntPtr writer);
    }
}
