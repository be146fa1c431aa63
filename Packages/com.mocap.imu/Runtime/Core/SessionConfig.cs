using System;

namespace Mocap.Imu
{
    /// <summary>Where a session's bytes come from (mocap_source_kind).</summary>
    public enum MocapSourceKind
    {
        /// <summary>A USB serial port: "/dev/ttyUSB0", "COM3".</summary>
        Serial = 0,
        /// <summary>A HiPNUC HID receiver, by vendor/product id or hidraw path.</summary>
        Hid = 1,
        /// <summary>A raw capture file written by the engine.</summary>
        Replay = 2,
    }

    /// <summary>Layout of HiPNUC 0x91 IMUSOL packets (mocap_imusol_layout).</summary>
    public enum MocapImusolLayout
    {
        /// <summary>Decide per packet when unambiguous, else the node id layout.</summary>
        Auto = 0,
        /// <summary>Older firmware: byte 1 is the node id.</summary>
        NodeId = 1,
        /// <summary>Newer firmware: bytes 1..2 status, 3 temperature, 4..7 pressure.</summary>
        StatusWord = 2,
    }

    /// <summary>The sensors' world frame convention (mocap_world_frame); used before calibration only.</summary>
    public enum MocapWorldFrame
    {
        /// <summary>X north, Y west, Z up.</summary>
        Nwu = 0,
        /// <summary>X east, Y north, Z up.</summary>
        Enu = 1,
    }

    /// <summary>
    /// Everything needed to open a <see cref="MocapSession"/>. A new instance holds the engine's
    /// own defaults (read from the library, so there is one source of truth): 460800 baud, node
    /// ids 0..5, 60 Hz output. Change what you need, or start from <see cref="Serial"/>,
    /// <see cref="Hid"/> or <see cref="Replay"/>.
    /// </summary>
    public sealed class SessionConfig
    {
        /// <summary>Source kind.</summary>
        public MocapSourceKind Source { get; set; }
        /// <summary>Serial port, hidraw path or capture file (at most 259 bytes of UTF-8).</summary>
        public string Path { get; set; } = string.Empty;
        /// <summary>Serial only: baud rate (any rate the OS accepts).</summary>
        public int Baud { get; set; }
        /// <summary>HID only, when <see cref="Path"/> is empty.</summary>
        public ushort HidVendorId { get; set; }
        /// <summary>HID only, when <see cref="Path"/> is empty.</summary>
        public ushort HidProductId { get; set; }
        /// <summary>Node id of the sensor on each <see cref="MocapSegment"/>; -1 = none. Length 6.</summary>
        public int[] NodeIds { get; } = new int[MocapSession.SensorCount];
        public MocapImusolLayout ImusolLayout { get; set; }
        public MocapWorldFrame WorldFrame { get; set; }
        /// <summary>Output frame rate, Hz.</summary>
        public float OutputRateHz { get; set; }
        /// <summary>How long to wait for late sensors before holding their last value, s.</summary>
        public float HoldLatencySeconds { get; set; }
        /// <summary>A sensor is stale after this long without data, s.</summary>
        public float StaleAfterSeconds { get; set; }
        /// <summary>Kalman acceleration random-walk spectral density, (m/s^3)^2/Hz.</summary>
        public float KalmanProcessNoise { get; set; }
        /// <summary>Kalman accelerometer noise variance, (m/s^2)^2.</summary>
        public float KalmanMeasurementNoise { get; set; }
        /// <summary>Replay only: true plays at the recorded pace, false as fast as possible.</summary>
        public bool ReplayRealtime { get; set; }
        /// <summary>Replay only, with <see cref="ReplayRealtime"/>: pace multiplier.</summary>
        public float ReplaySpeed { get; set; }
        /// <summary>Serial/HID: reopen the device after an unplug.</summary>
        public bool AutoReconnect { get; set; }
        /// <summary>When not empty, the raw byte stream is recorded to this capture file.</summary>
        public string CapturePath { get; set; } = string.Empty;

        /// <summary>The engine's defaults.</summary>
        public unsafe SessionConfig()
        {
            // Before the engine writes into our mirror, make sure the mirror is its layout.
            MocapEngine.EnsureCompatible();
            NativeSessionConfig native;
            NativeMethods.Check(NativeMethods.mocap_config_defaults(&native));
            FromNative(in native);
        }

        /// <summary>A serial port source, e.g. "/dev/ttyUSB0" or "COM3".</summary>
        public static SessionConfig Serial(string port, int baud = 460800)
        {
            return new SessionConfig { Source = MocapSourceKind.Serial, Path = port, Baud = baud };
        }

        /// <summary>A HID receiver found by vendor and product id.</summary>
        public static SessionConfig Hid(ushort vendorId, ushort productId)
        {
            return new SessionConfig
            {
                Source = MocapSourceKind.Hid, HidVendorId = vendorId, HidProductId = productId
            };
        }

        /// <summary>A HID receiver at a hidraw path.</summary>
        public static SessionConfig Hid(string path)
        {
            return new SessionConfig { Source = MocapSourceKind.Hid, Path = path };
        }

        /// <summary>A capture file played as fast as possible, or at its recorded pace.</summary>
        public static SessionConfig Replay(string capturePath, bool realtime = false, float speed = 1f)
        {
            return new SessionConfig
            {
                Source = MocapSourceKind.Replay, Path = capturePath, ReplayRealtime = realtime,
                ReplaySpeed = speed
            };
        }

        /// <summary>
        /// Whether <paramref name="other"/> reads the same sensors: same source kind, port/path
        /// (and HID ids) and node id per segment. Rates, filters, pacing and the capture path may
        /// differ: a calibration made for one applies to the other.
        /// </summary>
        public bool IsSameSource(SessionConfig other)
        {
            if (other == null || other.Source != Source) return false;
            if (!string.Equals(other.Path ?? string.Empty, Path ?? string.Empty, StringComparison.Ordinal)) return false;
            if (Source == MocapSourceKind.Hid && (other.HidVendorId != HidVendorId || other.HidProductId != HidProductId))
                return false;
            if (other.NodeIds.Length != NodeIds.Length) return false;
            for (int s = 0; s < NodeIds.Length; s++)
                if (other.NodeIds[s] != NodeIds[s]) return false;
            return true;
        }

        /// <summary>A copy (sessions keep their own, so later edits do not affect them).</summary>
        public SessionConfig Clone() => new SessionConfig(this);

        // Copies without asking the library for defaults again.
        SessionConfig(SessionConfig other)
        {
            Source = other.Source;
            Path = other.Path;
            Baud = other.Baud;
            HidVendorId = other.HidVendorId;
            HidProductId = other.HidProductId;
            Array.Copy(other.NodeIds, NodeIds, NodeIds.Length);
            ImusolLayout = other.ImusolLayout;
            WorldFrame = other.WorldFrame;
            OutputRateHz = other.OutputRateHz;
            HoldLatencySeconds = other.HoldLatencySeconds;
            StaleAfterSeconds = other.StaleAfterSeconds;
            KalmanProcessNoise = other.KalmanProcessNoise;
            KalmanMeasurementNoise = other.KalmanMeasurementNoise;
            ReplayRealtime = other.ReplayRealtime;
            ReplaySpeed = other.ReplaySpeed;
            AutoReconnect = other.AutoReconnect;
            CapturePath = other.CapturePath;
        }

        /// <summary>
        /// Fill the engine's struct. Range checks (rates, ids, speeds) are left to the engine,
        /// whose messages say what is wrong; only what C# alone can get wrong is checked here.
        /// </summary>
        internal unsafe void ToNative(out NativeSessionConfig native)
        {
            if (NodeIds.Length != MocapSession.SensorCount)
                throw new ArgumentException("NodeIds must have 6 entries", nameof(NodeIds));
            if (Baud < 0) throw new ArgumentOutOfRangeException(nameof(Baud), "baud must be positive");
            native = default;
            native.StructSize = (uint)sizeof(NativeSessionConfig);
            native.SourceKind = (int)Source;
            fixed (byte* path = native.Path)
                NativeText.ToBuffer(Path, path, NativeMethods.PathMax, nameof(Path));
            native.Baud = (uint)Baud;
            native.HidVendorId = HidVendorId;
            native.HidProductId = HidProductId;
            fixed (int* ids = native.NodeIds)
                for (int s = 0; s < MocapSession.SensorCount; s++) ids[s] = NodeIds[s];
            native.ImusolLayout = (int)ImusolLayout;
            native.WorldFrame = (int)WorldFrame;
            native.OutputRateHz = OutputRateHz;
            native.HoldLatencySeconds = HoldLatencySeconds;
            native.StaleAfterSeconds = StaleAfterSeconds;
            native.KalmanProcessNoise = KalmanProcessNoise;
            native.KalmanMeasurementNoise = KalmanMeasurementNoise;
            native.ReplayRealtime = ReplayRealtime ? 1 : 0;
            native.ReplaySpeed = ReplaySpeed;
            native.AutoReconnect = AutoReconnect ? 1 : 0;
            fixed (byte* capture = native.CapturePath)
                NativeText.ToBuffer(CapturePath, capture, NativeMethods.PathMax, nameof(CapturePath));
        }

        unsafe void FromNative(in NativeSessionConfig native)
        {
            Source = (MocapSourceKind)native.SourceKind;
            fixed (byte* path = native.Path) Path = NativeText.FromBuffer(path, NativeMethods.PathMax);
            Baud = (int)native.Baud;
            HidVendorId = native.HidVendorId;
            HidProductId = native.HidProductId;
            fixed (int* ids = native.NodeIds)
                for (int s = 0; s < MocapSession.SensorCount; s++) NodeIds[s] = ids[s];
            ImusolLayout = (MocapImusolLayout)native.ImusolLayout;
            WorldFrame = (MocapWorldFrame)native.WorldFrame;
            OutputRateHz = native.OutputRateHz;
            HoldLatencySeconds = native.HoldLatencySeconds;
            StaleAfterSeconds = native.StaleAfterSeconds;
            KalmanProcessNoise = native.KalmanProcessNoise;
            KalmanMeasurementNoise = native.KalmanMeasurementNoise;
            ReplayRealtime = native.ReplayRealtime != 0;
            ReplaySpeed = native.ReplaySpeed;
            AutoReconnect = native.AutoReconnect != 0;
            fixed (byte* capture = native.CapturePath)
                CapturePath = NativeText.FromBuffer(capture, NativeMethods.PathMax);
        }
    }
}
