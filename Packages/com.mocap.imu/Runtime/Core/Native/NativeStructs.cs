// Blittable mirrors of the structs in Native~/include/mocap_imu.h.
//
// Every mirrored type and field carries [NativeName] with its C name, so NativeLayoutTests can
// compare each one with the sizes and offsets the library reports (mocap_struct_layout) and
// C and C# cannot drift apart silently. Only blittable field types are used (no bool, no
// string, no managed arrays): the engine writes straight into these structs, also into
// caller-owned arrays, without any marshalling copy.

using System;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>
    /// Body segments a sensor can ride on (mocap_segment). The engine's segment table
    /// (<see cref="SegmentTable"/>) gives each its name, SMPL joint and default node; a test keeps
    /// these members equal to that table.
    /// </summary>
    public enum MocapSegment
    {
        Pelvis = 0,
        LeftWrist = 1,
        RightWrist = 2,
        LeftShin = 3,
        RightShin = 4,
        Head = 5,
        Chest = 6,
    }

    /// <summary>What a sensor gave one frame (mocap_sensor_state).</summary>
    public enum MocapSensorState
    {
        /// <summary>Samples bracketed the frame time: interpolated.</summary>
        Fresh = 0,
        /// <summary>No sample after the frame time yet: the last value is held.</summary>
        Holding = 1,
        /// <summary>Nothing for longer than the stale threshold: the held value is old.</summary>
        Silent = 2,
        /// <summary>Never sent a sample: the values are placeholders.</summary>
        Absent = 3,
    }

    /// <summary>Per-sensor flags of <see cref="MocapSensorFrame"/>.</summary>
    [Flags]
    public enum MocapSensorFlags : uint
    {
        None = 0,
        /// <summary>The sensor has produced a sample at some point: its values are meaningful.</summary>
        Valid = 1u << 0,
        /// <summary>No sample bracketed this frame: the last value is held.</summary>
        Held = 1u << 1,
        /// <summary>The last sample is older than the session's stale threshold.</summary>
        Stale = 1u << 2,
        /// <summary>The bone fields use a calibration (otherwise they are an upright preview).</summary>
        Calibrated = 1u << 3,
        /// <summary>Reserved by the engine.</summary>
        Extrapolated = 1u << 4,
    }

    /// <summary>Frame flags of <see cref="MocapFrame"/>.</summary>
    [Flags]
    public enum MocapFrameFlags : uint
    {
        None = 0,
        /// <summary>Every required (not optional) sensor has a calibration.</summary>
        Calibrated = 1u << 0,
        /// <summary>Every sensor had a fresh sample bracketing the frame.</summary>
        Complete = 1u << 1,
    }

    /// <summary>A vector of three floats (x, y, z), laid out like the engine's float[3].</summary>
    [Serializable]
    [StructLayout(LayoutKind.Sequential)]
    public struct MocapVector3
    {
        public float X, Y, Z;

        public MocapVector3(float x, float y, float z) { X = x; Y = y; Z = z; }

        public override string ToString() => $"({X:F4}, {Y:F4}, {Z:F4})";
    }

    /// <summary>
    /// A quaternion in the engine's (w, x, y, z) order, laid out like its float[4]. Note that
    /// UnityEngine.Quaternion's constructor takes (x, y, z, w).
    /// </summary>
    [Serializable]
    [StructLayout(LayoutKind.Sequential)]
    public struct MocapQuaternion
    {
        public float W, X, Y, Z;

        public MocapQuaternion(float w, float x, float y, float z) { W = w; X = x; Y = y; Z = z; }

        /// <summary>The identity rotation.</summary>
        public static MocapQuaternion Identity => new MocapQuaternion(1, 0, 0, 0);

        /// <summary>Angle in degrees of the rotation between two unit quaternions (0..180).</summary>
        public static double AngleDegrees(MocapQuaternion a, MocapQuaternion b)
        {
            // |dot| handles q and -q (the same rotation); clamp guards rounding above 1.
            double dot = Math.Abs((double)a.W * b.W + (double)a.X * b.X + (double)a.Y * b.Y +
                                  (double)a.Z * b.Z);
            return 2.0 * Math.Acos(Math.Min(1.0, dot)) * (180.0 / Math.PI);
        }

        public override string ToString() => $"({W:F5}, {X:F5}, {Y:F5}, {Z:F5})";
    }

    /// <summary>A row-major 3x3 rotation matrix, laid out like the engine's float[9].</summary>
    [Serializable]
    [StructLayout(LayoutKind.Sequential)]
    public struct MocapMatrix3x3
    {
        public float M00, M01, M02, M10, M11, M12, M20, M21, M22;

        /// <summary>The identity matrix.</summary>
        public static MocapMatrix3x3 Identity => new MocapMatrix3x3 { M00 = 1, M11 = 1, M22 = 1 };

        /// <summary>Element at row r, column c (0..2).</summary>
        public unsafe float this[int r, int c]
        {
            get
            {
                if ((uint)r > 2 || (uint)c > 2) throw new ArgumentOutOfRangeException();
                fixed (float* m = &M00) return m[r * 3 + c];
            }
            set
            {
                if ((uint)r > 2 || (uint)c > 2) throw new ArgumentOutOfRangeException();
                fixed (float* m = &M00) m[r * 3 + c] = value;
            }
        }
    }

    /// <summary>One sensor in one output frame (mocap_sensor_frame). All vectors in SI units.</summary>
    [Serializable]
    [NativeName("mocap_sensor_frame")]
    [StructLayout(LayoutKind.Sequential)]
    public struct MocapSensorFrame
    {
        /// <summary>
        /// Calibrated bone orientation, bone to model frame. Before calibration an upright
        /// preview (flag <see cref="MocapSensorFlags.Calibrated"/> clear); identity for a sensor
        /// that never sent data.
        /// </summary>
        [NativeName("bone_orientation")] public MocapQuaternion BoneOrientation;
        /// <summary>Bone-attached linear acceleration, model frame, gravity removed, m/s^2.</summary>
        [NativeName("bone_acceleration")] public MocapVector3 BoneAcceleration;
        /// <summary>Raw sensor orientation, sensor to sensor-world frame (Z up).</summary>
        [NativeName("sensor_orientation")] public MocapQuaternion SensorOrientation;
        /// <summary>Kalman-filtered specific force in the sensor world frame, m/s^2.</summary>
        [NativeName("world_specific_force")] public MocapVector3 WorldSpecificForce;
        /// <summary>Angular rate in the sensor frame, rad/s.</summary>
        [NativeName("angular_rate")] public MocapVector3 AngularRate;
        /// <summary>Seconds since this sensor's newest sample, at the frame time.</summary>
        [NativeName("age_s")] public float AgeSeconds;
        [NativeName("flags")] public MocapSensorFlags Flags;
        /// <summary>HiPNUC node id the sample came from.</summary>
        [NativeName("node_id")] public uint NodeId;
        /// <summary>The segment the sensor rides on (from the session config).</summary>
        [NativeName("segment")] public MocapSegment Segment;
        /// <summary>Fresh, holding, silent or absent this frame.</summary>
        [NativeName("state")] public MocapSensorState State;

        public bool IsCalibrated => (Flags & MocapSensorFlags.Calibrated) != 0;
        public bool IsValid => (Flags & MocapSensorFlags.Valid) != 0;
    }

    /// <summary>
    /// One synchronised output frame (mocap_frame). Drain these into a caller-owned array:
    /// the struct is blittable, so the engine writes it in place without any allocation.
    /// </summary>
    [Serializable]
    [NativeName("mocap_frame")]
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct MocapFrame
    {
        /// <summary>0, 1, 2 ... per session; a gap means frames were dropped.</summary>
        [NativeName("sequence")] public ulong Sequence;
        /// <summary>Frame time on the session clock, seconds.</summary>
        [NativeName("time_s")] public double TimeSeconds;
        /// <summary>Receive time of the newest bytes that fed this frame, ns (session clock).</summary>
        [NativeName("newest_receive_ns")] public long NewestReceiveNs;
        /// <summary>Session clock when the engine produced the frame, ns.</summary>
        [NativeName("emitted_ns")] public long EmittedNs;
        [NativeName("flags")] public MocapFrameFlags Flags;
        /// <summary>Bit i set: sensor i (config order) had a fresh sample for this frame.</summary>
        [NativeName("fresh_mask")] public uint FreshMask;
        [NativeName("sensor_count")] uint _sensorCount;
        [NativeName("reserved")] uint _reserved;
        // C has mocap_sensor_frame sensors[16]; C# 9 has no inline arrays of structs, so the
        // sixteen elements live in a fixed buffer of the same size, read through a pointer cast.
        [NativeName("sensors")] fixed uint _sensors[MocapSession.MaxSensors * SensorFrameWords];

        // sizeof(mocap_sensor_frame) / 4; the layout test checks the buffer against the engine.
        internal const int SensorFrameWords = 22;

        public bool IsCalibrated => (Flags & MocapFrameFlags.Calibrated) != 0;
        public bool IsComplete => (Flags & MocapFrameFlags.Complete) != 0;

        /// <summary>
        /// The session's sensors in this frame, in its config order (0..16). Set it when building
        /// frames by hand (recordings) before <see cref="SetSensor"/>.
        /// </summary>
        public int SensorCount
        {
            get => (int)_sensorCount;
            set
            {
                if ((uint)value > MocapSession.MaxSensors)
                    throw new ArgumentOutOfRangeException(nameof(value), value,
                        $"a frame holds at most {MocapSession.MaxSensors} sensors");
                _sensorCount = (uint)value;
            }
        }

        /// <summary>Whether sensor <paramref name="index"/> had a fresh sample for this frame.</summary>
        public bool IsFresh(int index) => (uint)index < 32 && (FreshMask & (1u << index)) != 0;

        /// <summary>Sensor <paramref name="index"/> (0 .. <see cref="SensorCount"/>-1), a copy; no allocation.</summary>
        public MocapSensorFrame GetSensor(int index)
        {
            if ((uint)index >= _sensorCount)
                throw new ArgumentOutOfRangeException(nameof(index), index, $"the frame has {_sensorCount} sensors");
            fixed (uint* words = _sensors) return ((MocapSensorFrame*)words)[index];
        }

        /// <summary>Replace sensor <paramref name="index"/> (0 .. <see cref="SensorCount"/>-1).</summary>
        public void SetSensor(int index, in MocapSensorFrame sensor)
        {
            if ((uint)index >= _sensorCount)
                throw new ArgumentOutOfRangeException(nameof(index), index, $"the frame has {_sensorCount} sensors");
            fixed (uint* words = _sensors) ((MocapSensorFrame*)words)[index] = sensor;
        }

        /// <summary>The index of the sensor on <paramref name="segment"/>, or -1 when the frame has none.</summary>
        public int IndexOf(MocapSegment segment)
        {
            fixed (uint* words = _sensors)
            {
                var sensors = (MocapSensorFrame*)words;
                for (int i = 0; i < (int)_sensorCount && i < MocapSession.MaxSensors; i++)
                    if (sensors[i].Segment == segment) return i;
            }
            return -1;
        }

        /// <summary>The sensor on <paramref name="segment"/>, when the frame has one; no allocation.</summary>
        public bool TryGetSensor(MocapSegment segment, out MocapSensorFrame sensor)
        {
            int index = IndexOf(segment);
            if (index < 0)
            {
                sensor = default;
                return false;
            }
            fixed (uint* words = _sensors) sensor = ((MocapSensorFrame*)words)[index];
            return true;
        }
    }

    /// <summary>Connection state of a session's source (mocap_connection_state).</summary>
    public enum MocapConnectionState
    {
        Closed = 0,
        Connected = 1,
        /// <summary>The device was lost; the engine reconnects when auto-reconnect is on.</summary>
        Disconnected = 2,
        /// <summary>A replay has delivered everything.</summary>
        Ended = 3,
    }

    /// <summary>Counters and health of a running session (mocap_session_stats).</summary>
    [NativeName("mocap_session_stats")]
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct MocapSessionStats
    {
        [NativeName("bytes_received")] public ulong BytesReceived;
        /// <summary>HiPNUC frames with a valid CRC.</summary>
        [NativeName("frames_decoded")] public ulong FramesDecoded;
        [NativeName("crc_failures")] public ulong CrcFailures;
        /// <summary>Garbage bytes discarded while resynchronising.</summary>
        [NativeName("bytes_skipped")] public ulong BytesSkipped;
        [NativeName("unknown_packets")] public ulong UnknownPackets;
        /// <summary>Per-sensor samples (a gateway frame gives several).</summary>
        [NativeName("samples_decoded")] public ulong SamplesDecoded;
        /// <summary>NaN/Inf, beyond any sensor's range, zero or non-unit quaternions, unknown nodes,
        /// older than a sample already taken.</summary>
        [NativeName("samples_rejected")] public ulong SamplesRejected;
        [NativeName("frames_emitted")] public ulong FramesEmitted;
        /// <summary>Output frames lost because the consumer polled too slowly.</summary>
        [NativeName("frames_dropped")] public ulong FramesDropped;
        /// <summary>Input bytes lost because processing was too slow.</summary>
        [NativeName("bytes_dropped")] public ulong BytesDropped;
        [NativeName("reconnects")] public ulong Reconnects;
        [NativeName("capture_bytes_written")] public ulong CaptureBytesWritten;
        /// <summary>Replay: damaged chunks of the capture passed over; what they held is missing
        /// from the frames.</summary>
        [NativeName("replay_chunks_skipped")] public ulong ReplayChunksSkipped;
        [NativeName("connection_state")] public MocapConnectionState ConnectionState;
        /// <summary>Status of the capture writer (<see cref="MocapStatus.Ok"/> when fine).</summary>
        [NativeName("capture_error")] public MocapStatus CaptureError;
        /// <summary>Bit i: sensor i (config order) has produced a sample.</summary>
        [NativeName("sensors_seen_mask")] public uint SensorsSeenMask;
        [NativeName("replay_tail_damaged")] private int _replayTailDamaged;
        [NativeName("last_error")] private fixed byte _lastError[256];

        /// <summary>Replay: the capture turned out to end in a damaged or incomplete chunk (a
        /// recording cut short), so its last records are missing from the frames.</summary>
        public bool ReplayTailDamaged => _replayTailDamaged != 0;

        /// <summary>Replay: what the damage passed over means for the poses, in one sentence, or
        /// "" for an undamaged capture. The component's status text and its inspector both show
        /// this, so they say the same thing. Allocates only for a damaged capture.</summary>
        public string ReplayDamage
        {
            get
            {
                bool tail = ReplayTailDamaged;
                if (ReplayChunksSkipped == 0)
                    return tail ? "The capture is cut short: its last records are missing from the poses." : "";
                return $"The capture is damaged: {ReplayChunksSkipped} chunk(s) passed over"
                       + (tail ? " and its end cut short" : "")
                       + "; what they held is missing from the poses.";
            }
        }

        /// <summary>The last asynchronous error (device lost, disk full ...), or "". Allocates.</summary>
        public string LastError
        {
            get { fixed (byte* p = _lastError) return NativeText.FromBuffer(p, 256); }
        }
    }

    /// <summary>
    /// mocap_session_config as the engine reads it. Internal: users fill the friendlier
    /// <see cref="SessionConfig"/>, which converts to this.
    /// </summary>
    [NativeName("mocap_session_config")]
    [StructLayout(LayoutKind.Sequential)]
    internal unsafe struct NativeSessionConfig
    {
        [NativeName("struct_size")] public uint StructSize;
        [NativeName("source_kind")] public int SourceKind;
        [NativeName("path")] public fixed byte Path[NativeMethods.PathMax];
        [NativeName("baud")] public uint Baud;
        [NativeName("hid_vendor_id")] public ushort HidVendorId;
        [NativeName("hid_product_id")] public ushort HidProductId;
        [NativeName("sensor_count")] public uint SensorCount;
        [NativeName("sensor_segments")] public fixed int SensorSegments[MocapSession.MaxSensors];
        [NativeName("node_ids")] public fixed int NodeIds[MocapSession.MaxSensors];
        [NativeName("optional_mask")] public uint OptionalMask;
        [NativeName("imusol_layout")] public int ImusolLayout;
        [NativeName("world_frame")] public int WorldFrame;
        [NativeName("output_rate_hz")] public float OutputRateHz;
        [NativeName("hold_latency_s")] public float HoldLatencySeconds;
        [NativeName("stale_after_s")] public float StaleAfterSeconds;
        [NativeName("kalman_process_noise")] public float KalmanProcessNoise;
        [NativeName("kalman_measurement_noise")] public float KalmanMeasurementNoise;
        [NativeName("replay_realtime")] public int ReplayRealtime;
        [NativeName("replay_speed")] public float ReplaySpeed;
        [NativeName("auto_reconnect")] public int AutoReconnect;
        [NativeName("capture_path")] public fixed byte CapturePath[NativeMethods.PathMax];
    }

    /// <summary>Marks a mirror of a C struct or field with its C name, for the layout test.</summary>
    [AttributeUsage(AttributeTargets.Struct | AttributeTargets.Field)]
    internal sealed class NativeNameAttribute : Attribute
    {
        public NativeNameAttribute(string name) { Name = name; }
        public string Name { get; }
    }

    /// <summary>One row of mocap_struct_layout(): a struct (FieldName "") or one of its fields.</summary>
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeFieldLayout
    {
        public IntPtr StructName;
        public IntPtr FieldName;
        public uint Offset;
        public uint Size;
    }
}
