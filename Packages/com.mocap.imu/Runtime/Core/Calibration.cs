using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;

namespace Mocap.Imu
{
    /// <summary>Calibration steps (mocap_calibration_step); see Native~/docs/calibration.md.</summary>
    public enum CalibrationStep
    {
        /// <summary>
        /// All sensors lie still, X axis pointing the way the user will face, Z up. Gives each
        /// sensor's world alignment.
        /// </summary>
        Heading = 0,
        /// <summary>
        /// Sensors strapped on, the user stands still in a T-pose facing forward. Gives each
        /// sensor's mounting rotation and acceleration offset.
        /// </summary>
        TPose = 1,
        /// <summary>
        /// Yaw-only re-alignment against drift: the user stands still, facing forward, upright.
        /// Mounting and offsets are kept.
        /// </summary>
        HeadingReset = 2,
    }

    /// <summary>Progress of a calibration request (mocap_calibration_state).</summary>
    public enum CalibrationState
    {
        Idle = 0,
        /// <summary>Scheduled; the window has not been reached yet.</summary>
        Waiting = 1,
        Collecting = 2,
        Accepted = 3,
        Refused = 4,
    }

    /// <summary>Quality of one sensor over a calibration window (mocap_sensor_quality).</summary>
    [NativeName("mocap_sensor_quality")]
    [StructLayout(LayoutKind.Sequential)]
    public struct SensorQuality
    {
        /// <summary>RMS angular rate over the window, deg/s (stillness).</summary>
        [NativeName("gyro_rms_dps")] public float GyroRmsDps;
        /// <summary>RMS angle of the orientations about their mean, degrees.</summary>
        [NativeName("orientation_spread_deg")] public float OrientationSpreadDegrees;
        /// <summary>| |mean specific force| - g |, m/s^2.</summary>
        [NativeName("accel_norm_error")] public float AccelerationNormError;
        /// <summary>Heading step: angle between the sensor's Z and world up, degrees.</summary>
        [NativeName("tilt_deg")] public float TiltDegrees;
        /// <summary>Frames with a fresh sample in the window.</summary>
        [NativeName("samples")] public uint Samples;
        [NativeName("ok")] int _ok;
        /// <summary>The segment the sensor rides on.</summary>
        [NativeName("segment")] public MocapSegment Segment;
        [NativeName("left_out")] int _leftOut;

        /// <summary>The sensor passed every check.</summary>
        public bool IsOk => _ok != 0;

        /// <summary>An optional sensor that sent nothing: left uncalibrated instead of refusing the step.</summary>
        public bool IsLeftOut => _leftOut != 0;
    }

    /// <summary>State and quality of a calibration step (mocap_calibration_report).</summary>
    [NativeName("mocap_calibration_report")]
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct CalibrationReport
    {
        [NativeName("step")] public CalibrationStep Step;
        [NativeName("state")] public CalibrationState State;
        /// <summary>0..1 through the collection window.</summary>
        [NativeName("progress")] public float Progress;
        [NativeName("seconds_remaining")] public float SecondsRemaining;
        [NativeName("sensor_count")] uint _sensorCount;
        // C: mocap_sensor_quality sensors[16], mirrored as a fixed buffer of the same size.
        [NativeName("sensors")] fixed uint _sensors[MocapSession.MaxSensors * SensorQualityWords];
        [NativeName("reason")] fixed byte _reason[256];

        // sizeof(mocap_sensor_quality) / 4; the layout test checks the buffer against the engine.
        const int SensorQualityWords = 8;

        /// <summary>The step has a result (accepted or refused).</summary>
        public bool IsFinished => State == CalibrationState.Accepted || State == CalibrationState.Refused;

        /// <summary>The session's sensors, in its config order.</summary>
        public int SensorCount => (int)Math.Min(_sensorCount, (uint)MocapSession.MaxSensors);

        /// <summary>Quality of sensor <paramref name="index"/> (0 .. <see cref="SensorCount"/>-1).</summary>
        public SensorQuality GetSensor(int index)
        {
            if ((uint)index >= (uint)SensorCount)
                throw new ArgumentOutOfRangeException(nameof(index), index, $"the report has {SensorCount} sensors");
            fixed (uint* words = _sensors) return ((SensorQuality*)words)[index];
        }

        /// <summary>The index of the sensor on <paramref name="segment"/>, or -1 when the session has none.</summary>
        public int IndexOf(MocapSegment segment)
        {
            fixed (uint* words = _sensors)
            {
                var sensors = (SensorQuality*)words;
                for (int i = 0; i < SensorCount; i++)
                    if (sensors[i].Segment == segment) return i;
            }
            return -1;
        }

        /// <summary>Quality of the sensor on <paramref name="segment"/>, when the session has one.</summary>
        public bool TryGetSensor(MocapSegment segment, out SensorQuality quality)
        {
            int index = IndexOf(segment);
            quality = index >= 0 ? GetSensor(index) : default;
            return index >= 0;
        }

        /// <summary>Why the step was refused, naming the sensor(s); "" otherwise. Allocates.</summary>
        public string Reason
        {
            get { fixed (byte* p = _reason) return NativeText.FromBuffer(p, 256); }
        }

        public override string ToString() =>
            State == CalibrationState.Refused ? $"{Step}: {State}: {Reason}" : $"{Step}: {State}";
    }

    /// <summary>
    /// The result of calibration (mocap_calibration): everything that turns raw sensor data into
    /// model-frame bones. Get it from <see cref="MocapSession.Calibration"/>, save it, load it
    /// later and set it on a new session to skip the calibration steps.
    /// </summary>
    [NativeName("mocap_calibration")]
    [StructLayout(LayoutKind.Sequential)]
    public unsafe struct CalibrationData
    {
        const int Max = MocapSession.MaxSensors;

        [NativeName("struct_size")] uint _structSize;
        [NativeName("sensor_count")] uint _sensorCount;
        /// <summary>Bit i: heading and T-pose both done for entry i.</summary>
        [NativeName("valid_mask")] public uint ValidMask;
        /// <summary>Bit i: heading done for entry i.</summary>
        [NativeName("heading_mask")] public uint HeadingMask;
        [NativeName("segments")] fixed int _segments[Max];
        [NativeName("world_to_model")] fixed float _worldToModel[Max * 9];
        [NativeName("sensor_to_bone")] fixed float _sensorToBone[Max * 9];
        [NativeName("acceleration_offset")] fixed float _accelerationOffset[Max * 3];

        /// <summary>
        /// Entries, one per sensor (config order of the session it came from). Applied to a
        /// session, each entry goes to the session's sensor on the same segment.
        /// </summary>
        public int SensorCount => (int)Math.Min(_sensorCount, (uint)Max);

        /// <summary>The segment of entry <paramref name="index"/>.</summary>
        public MocapSegment GetSegment(int index) => (MocapSegment)_segments[Entry(index)];

        /// <summary>The entry of <paramref name="segment"/>, or -1 when this calibration has none.</summary>
        public int IndexOf(MocapSegment segment)
        {
            for (int i = 0; i < SensorCount; i++)
                if (_segments[i] == (int)segment) return i;
            return -1;
        }

        /// <summary>
        /// Append an uncalibrated entry for <paramref name="segment"/> (building a calibration by
        /// hand); returns its index.
        /// </summary>
        public int AddSensor(MocapSegment segment)
        {
            if (IndexOf(segment) >= 0)
                throw new ArgumentException($"the calibration already has an entry for {SegmentTable.SnakeName(segment)}", nameof(segment));
            if (SensorCount >= Max)
                throw new InvalidOperationException($"a calibration holds at most {Max} sensors");
            int index = SensorCount;
            _segments[index] = (int)segment;
            _sensorCount = (uint)(index + 1);
            return index;
        }

        /// <summary>Every entry has heading and T-pose (and there is at least one).</summary>
        public bool IsComplete
        {
            get
            {
                int n = SensorCount;
                uint all = n >= 32 ? uint.MaxValue : (1u << n) - 1u;
                return n > 0 && (ValidMask & all) == all;
            }
        }

        /// <summary>Heading and T-pose are both done for the sensor on a segment (false when it has no entry).</summary>
        public bool IsValid(MocapSegment segment)
        {
            int i = IndexOf(segment);
            return i >= 0 && (ValidMask & (1u << i)) != 0;
        }

        /// <summary>Sensor world to model frame (a yaw about up, then Z-up to Y-up) of entry <paramref name="index"/>.</summary>
        public MocapMatrix3x3 GetWorldToModel(int index)
        {
            fixed (float* m = _worldToModel) return *(MocapMatrix3x3*)(m + Entry(index) * 9);
        }

        public void SetWorldToModel(int index, in MocapMatrix3x3 value)
        {
            fixed (float* m = _worldToModel) *(MocapMatrix3x3*)(m + Entry(index) * 9) = value;
        }

        /// <summary>Sensor frame to bone frame (the mounting rotation) of entry <paramref name="index"/>.</summary>
        public MocapMatrix3x3 GetSensorToBone(int index)
        {
            fixed (float* m = _sensorToBone) return *(MocapMatrix3x3*)(m + Entry(index) * 9);
        }

        public void SetSensorToBone(int index, in MocapMatrix3x3 value)
        {
            fixed (float* m = _sensorToBone) *(MocapMatrix3x3*)(m + Entry(index) * 9) = value;
        }

        /// <summary>Model-frame specific force at the T-pose (gravity plus bias), m/s^2, of entry <paramref name="index"/>.</summary>
        public MocapVector3 GetAccelerationOffset(int index)
        {
            fixed (float* v = _accelerationOffset) return *(MocapVector3*)(v + Entry(index) * 3);
        }

        public void SetAccelerationOffset(int index, MocapVector3 value)
        {
            fixed (float* v = _accelerationOffset) *(MocapVector3*)(v + Entry(index) * 3) = value;
        }

        /// <summary>The entry of <paramref name="segment"/>; throws naming it when there is none.</summary>
        public int EntryOf(MocapSegment segment)
        {
            int i = IndexOf(segment);
            if (i < 0)
                throw new ArgumentException($"the calibration has no entry for {SegmentTable.SnakeName(segment)}", nameof(segment));
            return i;
        }

        /// <summary>
        /// Save as the engine's small versioned text file (written to a temporary file and
        /// renamed, so a crash never leaves half a file).
        /// </summary>
        public void Save(string path)
        {
            MocapEngine.EnsureCompatible();
            var utf8 = NativeText.ToNullTerminated(path, nameof(path));
            CalibrationData copy = WithStructSize();
            fixed (byte* p = utf8) NativeMethods.Check(NativeMethods.mocap_calibration_save(&copy, p));
        }

        /// <summary>
        /// Load a file written by <see cref="Save"/> (or mocapctl). Throws
        /// <see cref="MocapException"/> with <see cref="MocapStatus.NotFound"/> or
        /// <see cref="MocapStatus.Format"/> and a message naming the file and line.
        /// </summary>
        public static CalibrationData Load(string path)
        {
            // The engine writes its own sizeof(mocap_calibration) into the result: a library of
            // another API version must be refused before that, not after.
            MocapEngine.EnsureCompatible();
            var utf8 = NativeText.ToNullTerminated(path, nameof(path));
            CalibrationData result;
            fixed (byte* p = utf8) NativeMethods.Check(NativeMethods.mocap_calibration_load(p, &result));
            return result;
        }

        /// <summary>
        /// A copy with struct_size set: a default(CalibrationData) the caller filled by hand has
        /// 0 there, which the engine would refuse as a version mismatch.
        /// </summary>
        internal CalibrationData WithStructSize()
        {
            CalibrationData copy = this;
            copy._structSize = (uint)sizeof(CalibrationData);
            return copy;
        }

        int Entry(int index)
        {
            if ((uint)index >= (uint)SensorCount)
                throw new ArgumentOutOfRangeException(nameof(index), index, $"the calibration has {SensorCount} entries");
            return index;
        }
    }

    /// <summary>Which calibrations survive when a set of sessions is opened again.</summary>
    public static class CalibrationCarry
    {
        /// <summary>
        /// The calibration for each of <paramref name="next"/> taken from the sessions opened with
        /// <paramref name="previous"/> (<paramref name="calibrations"/>[i] belongs to previous[i];
        /// null = none). A calibration is carried only when the number of sessions is unchanged
        /// and session i reads the same sensors as before (<see cref="SessionConfig.IsSameSource"/>):
        /// after characters were added, removed or reordered, a calibration would belong to another
        /// character's sensors. Always returns an array of next.Count entries.
        /// </summary>
        public static CalibrationData?[] Match(IReadOnlyList<SessionConfig> previous,
                                              IReadOnlyList<CalibrationData?> calibrations,
                                              IReadOnlyList<SessionConfig> next)
        {
            if (next == null) throw new ArgumentNullException(nameof(next));
            var carried = new CalibrationData?[next.Count];
            if (previous == null || calibrations == null) return carried;
            if (previous.Count != next.Count || calibrations.Count != next.Count) return carried;
            for (int i = 0; i < carried.Length; i++)
                if (previous[i] != null && previous[i].IsSameSource(next[i])) carried[i] = calibrations[i];
            return carried;
        }
    }
}
