// Layout mirrors of the streaming and export structs (Native~/include/mocap_imu.h, "Streaming and
// export": VMC sender and BVH writer). Only the mirrors NativeLayoutTests needs to check every
// struct the engine reports; the C# wrappers (VMC from the Unity session, editor BVH export) build
// on these.

using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    [NativeName("mocap_vmc_options")]
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeVmcOptions
    {
        [NativeName("struct_size")] public uint StructSize;
        [NativeName("max_rate_hz")] public float MaxRateHz;
        [NativeName("allow_remote")] public int AllowRemote;
        [NativeName("calibration_state")] public int CalibrationState;
    }

    [NativeName("mocap_vmc_stats")]
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeVmcStats
    {
        [NativeName("poses")] public ulong Poses;
        [NativeName("bundles_sent")] public ulong BundlesSent;
        [NativeName("skipped_rate")] public ulong SkippedRate;
        [NativeName("send_failures")] public ulong SendFailures;
        [NativeName("bytes_sent")] public ulong BytesSent;
        [NativeName("bones_per_bundle")] public uint BonesPerBundle;
        [NativeName("last_bundle_size")] public uint LastBundleSize;
    }

    [NativeName("mocap_bvh_options")]
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeBvhOptions
    {
        [NativeName("struct_size")] public uint StructSize;
        [NativeName("rotation_order")] public int RotationOrder;
        [NativeName("frame_rate")] public float FrameRate;
        [NativeName("flush_every")] public uint FlushEvery;
    }
}
