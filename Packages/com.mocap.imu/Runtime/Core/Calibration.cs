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

        /// <summary>The sensor passed every check.</summary>
        public bool IsOk => _ok != 0;
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
        // C: mocap_sensor_quality sensors[6], mirrored as six consecutive fields.
        [NativeName("sensors", Count = MocapSession.SensorCount)] SensorQuality _sensor0;
        SensorQuality _sensor1, _sensor2, _sensor3, _sensor4, _sensor5;
        [NativeName("reason")] fixed byte _reason[256];

        /// <summary>The step has a result (accepted or refused).</summary>
        public bool IsFinished => State == CalibrationState.Accepted || State == CalibrationState.Refused;

        /// <summary>Quality of one sensor.</summary>
        public SensorQuality GetSensor(MocapSegment segment)
        {
            if ((uint)segment >= MocapSession.SensorCount)
                throw new ArgumentOutOfRangeException(nameof(segment));
            fixed (SensorQuality* first = &_sensor0) return first[(int)segment];
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
        const int Count = MocapSession.SensorCount;

        [NativeName("struct_size")] uint _structSize;
        /// <summary>Bit s: heading and T-pose both done for segment s.</summary>
        [NativeName("valid_mask")] public uint ValidMask;
        /// <summary>Bit s: heading done for segment s.</summary>
        [NativeName("heading_mask")] public uint HeadingMask;
        [NativeName("reserved")] uint _reserved;
        [NativeName("world_to_model")] fixed float _worldToModel[Count * 9];
        [NativeName("sensor_to_bone")] fixed float _sensorToBone[Count * 9];
        [NativeName("acceleration_offset")] fixed float _accelerationOffset[Count * 3];

        /// <summary>Every segment has a complete calibration.</summary>
        public bool IsComplete => (ValidMask & 0x3Fu) == 0x3Fu;

        /// <summary>Heading and T-pose are both done for a segment.</summary>
        public bool IsValid(MocapSegment segment) => (ValidMask & (1u << (int)segment)) != 0;

        /// <summary>Sensor world to model frame (a yaw about up, then Z-up to Y-up).</summary>
        public MocapMatrix3x3 GetWorldToModel(MocapSegment segment)
        {
            fixed (float* m = _worldToModel) return ReadMatrix(m, segment);
        }

        public void SetWorldToModel(MocapSegment segment, in MocapMatrix3x3 value)
        {
            fixed (float* m = _worldToModel) WriteMatrix(m, segment, value);
        }

        /// <summary>Sensor frame to bone frame (the mounting rotation).</summary>
        public MocapMatrix3x3 GetSensorToBone(MocapSegment segment)
        {
            fixed (float* m = _sensorToBone) return ReadMatrix(m, segment);
        }

        public void SetSensorToBone(MocapSegment segment, in MocapMatrix3x3 value)
        {
            fixed (float* m = _sensorToBone) WriteMatrix(m, segment, value);
        }

        /// <summary>Model-frame specific force at the T-pose (gravity plus bias), m/s^2.</summary>
        public MocapVector3 GetAccelerationOffset(MocapSegment segment)
        {
            int s = Index(segment);
            fixed (float* v = _accelerationOffset) return *(MocapVector3*)(v + s * 3);
        }

        public void SetAccelerationOffset(MocapSegment segment, MocapVector3 value)
        {
            int s = Index(segment);
            fixed (float* v = _accelerationOffset) *(MocapVector3*)(v + s * 3) = value;
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

        static int Index(MocapSegment segment)
        {
            if ((uint)segment >= Count) throw new ArgumentOutOfRangeException(nameof(segment));
            return (int)segment;
        }

        static MocapMatrix3x3 ReadMatrix(float* matrices, MocapSegment segment) =>
            *(MocapMatrix3x3*)(matrices + Index(segment) * 9);

        static void WriteMatrix(float* matrices, MocapSegment segment, in MocapMatrix3x3 value) =>
            *(MocapMatrix3x3*)(matrices + Index(segment) * 9) = value;
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
