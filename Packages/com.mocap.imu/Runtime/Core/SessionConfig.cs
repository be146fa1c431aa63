using System;
using System.Collections.Generic;

namespace Mocap.Imu
{
    /// <summary>One sensor of a session's sensor set: the segment it rides on and the HiPNUC node it sends as.</summary>
    public readonly struct SessionSensor : IEquatable<SessionSensor>
    {
        public SessionSensor(MocapSegment segment, int nodeId, bool optional = false)
        {
            Segment = segment;
            NodeId = nodeId;
            Optional = optional;
        }

        /// <summary>The body segment.</summary>
        public MocapSegment Segment { get; }
        /// <summary>The HiPNUC node id (0..255).</summary>
        public int NodeId { get; }
        /// <summary>
        /// It may be missing: calibration leaves it out instead of refusing, and frames count as
        /// calibrated without it. Set from the model's optional sensors by the runner.
        /// </summary>
        public bool Optional { get; }

        /// <summary>The same sensor with another optional flag.</summary>
        public SessionSensor WithOptional(bool optional) => new SessionSensor(Segment, NodeId, optional);

        public bool Equals(SessionSensor other) =>
            Segment == other.Segment && NodeId == other.NodeId && Optional == other.Optional;

        public override bool Equals(object obj) => obj is SessionSensor other && Equals(other);

        public override int GetHashCode() => ((int)Segment * 397) ^ (NodeId * 2) ^ (Optional ? 1 : 0);

        public override string ToString() =>
            $"{SegmentTable.SnakeName(Segment)}={NodeId}" + (Optional ? " (optional)" : "");
    }

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
    /// own defaults (read from the library, so there is one source of truth): 460800 baud, the
    /// default sensor set (six sensors, node ids 0..5), 60 Hz output. Change what you need, or start from <see cref="Serial"/>,
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
        /// <summary>
        /// The sensor set, 1 to <see cref="MocapSession.MaxSensors"/> sensors, each segment and
        /// node id at most once. Frames, calibration reports and calibrations list the sensors in
        /// this order. Defaults to the engine's default set.
        /// </summary>
        public List<SessionSensor> Sensors { get; } = new List<SessionSensor>();
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

        /// <summary>Add a sensor to the set (the checks happen when the session opens).</summary>
        public SessionConfig AddSensor(MocapSegment segment, int nodeId, bool optional = false)
        {
            Sensors.Add(new SessionSensor(segment, nodeId, optional));
            return this;
        }

        /// <summary>The index of the sensor on <paramref name="segment"/> in <see cref="Sensors"/>, or -1.</summary>
        public int IndexOf(MocapSegment segment)
        {
            for (int i = 0; i < Sensors.Count; i++)
                if (Sensors[i].Segment == segment) return i;
            return -1;
        }

        /// <summary>
        /// Marks as optional each sensor <paramref name="model"/> does not require: one it lists
        /// as optional, and one it does not read at all. Such a sensor being absent then does not
        /// block calibration (as mocapctl does with a model). Sensors already optional stay so.
        /// </summary>
        public void MarkModelOptionalSensors(ModelInfo model)
        {
            if (model == null) throw new ArgumentNullException(nameof(model));
            for (int i = 0; i < Sensors.Count; i++)
            {
                int k = model.IndexOf(Sensors[i].Segment);
                bool required = k >= 0 && model.Sensors[k].Required;
                if (!required && !Sensors[i].Optional) Sensors[i] = Sensors[i].WithOptional(true);
            }
        }

        /// <summary>
        /// Whether <paramref name="other"/> reads the same sensors: same source kind, port/path
        /// (and HID ids) and the same node id on each segment. Rates, filters, pacing and the capture path may
        /// differ: a calibration made for one applies to the other.
        /// </summary>
        public bool IsSameSource(SessionConfig other)
        {
            if (other == null || other.Source != Source) return false;
            if (!string.Equals(other.Path ?? string.Empty, Path ?? string.Empty, StringComparison.Ordinal)) return false;
            if (Source == MocapSourceKind.Hid && (other.HidVendorId != HidVendorId || other.HidProductId != HidProductId))
                return false;
            // A calibration belongs to segments, not positions: the order may differ.
            if (other.Sensors.Count != Sensors.Count) return false;
            foreach (var sensor in Sensors)
            {
                int i = other.IndexOf(sensor.Segment);
                if (i < 0 || other.Sensors[i].NodeId != sensor.NodeId) return false;
            }
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
            Sensors.AddRange(other.Sensors);
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
        /// Fill the engine's struct. Range checks (rates, node ids, speeds) are left to the engine,
        /// whose messages say what is wrong; the sensor set is checked here, where the message
        /// can name the sensors as the caller wrote them.
        /// </summary>
        internal unsafe void ToNative(out NativeSessionConfig native)
        {
            CheckSensors();
            if (Baud < 0) throw new ArgumentOutOfRangeException(nameof(Baud), "baud must be positive");
            native = default;
            native.StructSize = (uint)sizeof(NativeSessionConfig);
            native.SourceKind = (int)Source;
            fixed (byte* path = native.Path)
                NativeText.ToBuffer(Path, path, NativeMethods.PathMax, nameof(Path));
            native.Baud = (uint)Baud;
            native.HidVendorId = HidVendorId;
            native.HidProductId = HidProductId;
            native.SensorCount = (uint)Sensors.Count;
            for (int i = 0; i < Sensors.Count; i++)
            {
                native.SensorSegments[i] = (int)Sensors[i].Segment;
                native.NodeIds[i] = Sensors[i].NodeId;
                if (Sensors[i].Optional) native.OptionalMask |= 1u << i;
            }
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
            Sensors.Clear();
            int count = (int)Math.Min(native.SensorCount, (uint)MocapSession.MaxSensors);
            fixed (NativeSessionConfig* n = &native)
                for (int i = 0; i < count; i++)
                    Sensors.Add(new SessionSensor((MocapSegment)n->SensorSegments[i], n->NodeIds[i],
                                                  (n->OptionalMask & (1u << i)) != 0));
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

        void CheckSensors()
        {
            if (Sensors.Count == 0)
                throw new ArgumentException("the session has no sensors: add at least one to Sensors", nameof(Sensors));
            if (Sensors.Count > MocapSession.MaxSensors)
                throw new ArgumentException(
                    $"the session has {Sensors.Count} sensors; the engine takes at most {MocapSession.MaxSensors}",
                    nameof(Sensors));
            for (int i = 0; i < Sensors.Count; i++)
                for (int j = 0; j < i; j++)
                {
                    if (Sensors[j].Segment == Sensors[i].Segment)
                        throw new ArgumentException(
                            $"sensors {j} and {i} are both on {SegmentTable.SnakeName(Sensors[i].Segment)}: each segment at most once",
                            nameof(Sensors));
                    if (Sensors[j].NodeId == Sensors[i].NodeId)
                        throw new ArgumentException(
                            $"sensors {j} ({SegmentTable.SnakeName(Sensors[j].Segment)}) and {i} " +
                            $"({SegmentTable.SnakeName(Sensors[i].Segment)}) both use node id {Sensors[i].NodeId}: each node id at most once",
                            nameof(Sensors));
                }
        }
    }
}
