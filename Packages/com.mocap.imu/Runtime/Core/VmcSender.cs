using System;

namespace Mocap.Imu
{
    /// <summary>How a <see cref="VmcSender"/> sends (mocap_vmc_options). A new instance holds the engine's defaults.</summary>
    public sealed class VmcOptions
    {
        /// <summary>The engine's defaults: 60 bundles/s at most, loopback only, calibration state 3.</summary>
        public unsafe VmcOptions()
        {
            MocapEngine.EnsureCompatible();
            NativeVmcOptions native;
            NativeMethods.Check(NativeVmcMethods.mocap_vmc_options_defaults(&native));
            MaxRateHz = native.MaxRateHz;
            AllowRemote = native.AllowRemote != 0;
            CalibrationState = native.CalibrationState;
        }

        /// <summary>At most this many bundles per second of pose time; 0 or less: every pose.</summary>
        public float MaxRateHz { get; set; }

        /// <summary>
        /// Allow destinations that are not loopback. Off by default: a pose stream names where a
        /// person is, so sending it across the network is an explicit choice.
        /// </summary>
        public bool AllowRemote { get; set; }

        /// <summary>Sent in /VMC/Ext/OK: 3 = calibrated (default); -1 sends only "/VMC/Ext/OK 1".</summary>
        public int CalibrationState { get; set; }

        internal unsafe void ToNative(out NativeVmcOptions native)
        {
            fixed (NativeVmcOptions* p = &native)
                NativeMethods.Check(NativeVmcMethods.mocap_vmc_options_defaults(p));
            native.MaxRateHz = MaxRateHz;
            native.AllowRemote = AllowRemote ? 1 : 0;
            native.CalibrationState = CalibrationState;
        }
    }

    /// <summary>What <see cref="VmcSender.Send"/> did with a pose.</summary>
    public enum VmcSendResult
    {
        /// <summary>One bundle went out.</summary>
        Sent = 0,
        /// <summary>The rate cap skipped the pose (not a failure).</summary>
        RateLimited = 1,
        /// <summary>The OS refused the datagram (nobody listening on some systems, network down); counted in <see cref="VmcStats.SendFailures"/>.</summary>
        Failed = 2,
    }

    /// <summary>Counters of a <see cref="VmcSender"/> (mocap_vmc_stats).</summary>
    public readonly struct VmcStats
    {
        internal VmcStats(in NativeVmcStats n)
        {
            Poses = n.Poses;
            BundlesSent = n.BundlesSent;
            SkippedRate = n.SkippedRate;
            SendFailures = n.SendFailures;
            BytesSent = n.BytesSent;
            BonesPerBundle = n.BonesPerBundle;
            LastBundleSize = n.LastBundleSize;
        }

        /// <summary>Valid poses handed to <see cref="VmcSender.Send"/>.</summary>
        public ulong Poses { get; }
        /// <summary>Bundles sent.</summary>
        public ulong BundlesSent { get; }
        /// <summary>Poses skipped by the rate cap.</summary>
        public ulong SkippedRate { get; }
        /// <summary>Datagrams the OS refused.</summary>
        public ulong SendFailures { get; }
        /// <summary>Bytes sent.</summary>
        public ulong BytesSent { get; }
        /// <summary>/VMC/Ext/Bone/Pos messages in the last bundle.</summary>
        public uint BonesPerBundle { get; }
        /// <summary>Size of the last bundle, bytes.</summary>
        public uint LastBundleSize { get; }
    }

    /// <summary>
    /// Streams one character's poses to one VMC receiver (VSeeFace, VNyan, Warudo, a VMC-enabled
    /// Unity app) as OSC bundles over UDP: one bundle per pose with the root and the 22 humanoid
    /// bones named as Unity's HumanBodyBones, in Unity's coordinates (see the C header for the
    /// exact messages). Several characters or several receivers: one sender each.
    /// </summary>
    /// <remarks>
    /// <para>The sender keeps its own copy of the model's skeleton description (joint names,
    /// parents, rest offsets), so the model may be disposed before it.</para>
    /// <para>Threads: one thread at a time per sender (in Unity the main thread).
    /// <see cref="Send"/> allocates nothing, also when the OS refuses a datagram.</para>
    /// </remarks>
    public sealed class VmcSender : IDisposable
    {
        /// <summary>VMC's usual performer port on this machine.</summary>
        public const string DefaultDestination = "127.0.0.1:39539";

        readonly VmcHandle _handle;
        // A class field, pinned by `fixed` for each send: no GC handle to keep, nothing allocated.
        NativeModelInfo _info;
        bool _disposed;

        VmcSender(VmcHandle handle, in NativeModelInfo info, string destination)
        {
            _handle = handle;
            _info = info;
            Destination = destination;
        }

        /// <summary>
        /// Open a sender to <paramref name="destination"/> ("host:port", "[v6]:port", "host", or
        /// null/"" for <see cref="DefaultDestination"/>), resolved once, for poses of
        /// <paramref name="model"/>.
        /// </summary>
        /// <exception cref="MocapException">A bad destination (named in the message), or
        /// <see cref="MocapStatus.Permission"/> for a non-loopback one without
        /// <see cref="VmcOptions.AllowRemote"/>.</exception>
        public static unsafe VmcSender Open(MocapModel model, string destination = null, VmcOptions options = null)
        {
            if (model == null) throw new ArgumentNullException(nameof(model));
            MocapEngine.EnsureCompatible();
            NativeModelInfo info;
            NativeMethods.Check(NativeSolverMethods.mocap_model_get_info(model.Handle, &info));
            (options ?? new VmcOptions()).ToNative(out var native);
            string text = string.IsNullOrEmpty(destination) ? DefaultDestination : destination;
            byte[] utf8 = NativeText.ToNullTerminated(text, nameof(destination));
            IntPtr vmc;
            MocapStatus status;
            fixed (byte* d = utf8)
                status = NativeVmcMethods.mocap_vmc_open(d, &native, out vmc);
            if (status != MocapStatus.Ok) throw NativeMethods.Failure(status);
            return new VmcSender(new VmcHandle(vmc), in info, text);
        }

        /// <summary>Where the bundles go, as given to <see cref="Open"/>.</summary>
        public string Destination { get; }

        /// <summary>
        /// Send one pose as one bundle. Returns <see cref="VmcSendResult.RateLimited"/> when the
        /// rate cap skipped it and <see cref="VmcSendResult.Failed"/> when the OS refused the
        /// datagram. Allocates nothing.
        /// </summary>
        /// <exception cref="MocapException">The pose is invalid (non-finite values) or the
        /// sender is unusable; these allocate, as exceptions do.</exception>
        public unsafe VmcSendResult Send(in MocapPose pose)
        {
            var handle = Handle;
            MocapStatus status;
            fixed (NativeModelInfo* info = &_info)
            fixed (MocapPose* p = &pose)
                status = NativeVmcMethods.mocap_vmc_send_pose(handle, info, p);
            switch (status)
            {
                case MocapStatus.Ok: return VmcSendResult.Sent;
                case MocapStatus.NoData: return VmcSendResult.RateLimited;
                case MocapStatus.IO: return VmcSendResult.Failed;
                default: throw NativeMethods.Failure(status);
            }
        }

        /// <summary>Counters since <see cref="Open"/>. Allocates nothing.</summary>
        public unsafe VmcStats GetStats()
        {
            NativeVmcStats stats;
            NativeMethods.Check(NativeVmcMethods.mocap_vmc_get_stats(Handle, &stats));
            return new VmcStats(in stats);
        }

        /// <summary>Close the socket.</summary>
        public void Dispose()
        {
            if (_disposed) return;
            _disposed = true;
            _handle.Dispose();
        }

        VmcHandle Handle
        {
            get
            {
                if (_disposed) throw new ObjectDisposedException(nameof(VmcSender), Destination);
                return _handle;
            }
        }
    }
}
