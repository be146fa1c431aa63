// Per-sensor calibration quality for people: each number of a SensorQuality against the engine's
// acceptance limit (Native~/docs/calibration.md, "Acceptance checks"), a 0..1 stillness score for
// a bar, and the checks that failed. The Calibration window and the run-time overlay draw these;
// no Unity here.

using System;
using System.Collections.Generic;
using System.Globalization;

namespace Mocap.Imu
{
    /// <summary>The engine's per-sensor acceptance limits (src/imu/calibration.c).</summary>
    public static class CalibrationLimits
    {
        /// <summary>RMS angular rate, deg/s (movement).</summary>
        public const float GyroRmsDps = 10f;
        /// <summary>RMS angle about the mean orientation, degrees (slow movement).</summary>
        public const float OrientationSpreadDegrees = 3f;
        /// <summary>| |mean force| - g |, m/s^2 (movement; g vs m/s^2 mix-ups). Not for the heading reset.</summary>
        public const float AccelerationNormError = 1.5f;
        /// <summary>Angle of the sensor's Z from up, degrees (heading step only: the sensor must lie flat).</summary>
        public const float TiltDegrees = 30f;
        /// <summary>Fresh samples needed, as a fraction of the frames in the window.</summary>
        public const float MinSampleFraction = 0.5f;
    }

    /// <summary>One sensor's calibration quality, ready to draw.</summary>
    public readonly struct SensorQualitySummary
    {
        public SensorQualitySummary(MocapSegment segment, SensorQuality quality, float stillness, string text,
                                    IReadOnlyList<string> problems)
        {
            Segment = segment;
            Quality = quality;
            Stillness = stillness;
            Text = text;
            Problems = problems;
        }

        /// <summary>The sensor.</summary>
        public MocapSegment Segment { get; }
        /// <summary>The engine's numbers.</summary>
        public SensorQuality Quality { get; }
        /// <summary>
        /// 1 = perfectly still, 0 = at or beyond a stillness limit (the worse of gyro RMS and
        /// orientation spread, each relative to its limit).
        /// </summary>
        public float Stillness { get; }
        /// <summary>The numbers with their limits, e.g. "gyro 0.4/10 deg/s, spread 0.1/3 deg, ...".</summary>
        public string Text { get; }
        /// <summary>Checks over their limit, e.g. "gyro 30.2 deg/s > 10"; empty when none.</summary>
        public IReadOnlyList<string> Problems { get; }
        /// <summary>The engine accepted this sensor.</summary>
        public bool IsOk => Quality.IsOk;
        /// <summary>An optional sensor that sent nothing, left uncalibrated (not a refusal).</summary>
        public bool IsLeftOut => Quality.IsLeftOut;
    }

    /// <summary>Turns calibration reports into per-sensor summaries.</summary>
    public static class CalibrationQuality
    {
        static readonly CultureInfo Invariant = CultureInfo.InvariantCulture;

        /// <summary>The sensor's display name ("left wrist").</summary>
        public static string SensorName(MocapSegment segment) => SegmentTable.DisplayName(segment);

        /// <summary>0..1 stillness of a sensor (see <see cref="SensorQualitySummary.Stillness"/>).</summary>
        public static float Stillness(in SensorQuality quality)
        {
            if (quality.Samples == 0) return 0f;
            float gyro = Ratio(quality.GyroRmsDps, CalibrationLimits.GyroRmsDps);
            float spread = Ratio(quality.OrientationSpreadDegrees, CalibrationLimits.OrientationSpreadDegrees);
            float worst = Math.Max(gyro, spread);
            return worst >= 1f ? 0f : 1f - worst;
        }

        /// <summary>Summaries of every sensor of a report, in the session's sensor order.</summary>
        public static SensorQualitySummary[] Summarize(in CalibrationReport report)
        {
            var result = new SensorQualitySummary[report.SensorCount];
            for (int s = 0; s < result.Length; s++)
            {
                var quality = report.GetSensor(s);
                result[s] = Summarize(report.Step, quality.Segment, quality);
            }
            return result;
        }

        /// <summary>One sensor's summary for a step (the checks that apply to that step only).</summary>
        public static SensorQualitySummary Summarize(CalibrationStep step, MocapSegment segment, in SensorQuality q)
        {
            var problems = new List<string>();
            var text = new List<string>();
            if (q.IsLeftOut)
                text.Add("left out: optional and sent nothing");
            else if (q.Samples == 0)
            {
                problems.Add("no samples");
                text.Add("no samples");
            }
            else
            {
                text.Add(Format("gyro {0:0.0}/{1:0} deg/s", q.GyroRmsDps, CalibrationLimits.GyroRmsDps));
                if (!(q.GyroRmsDps <= CalibrationLimits.GyroRmsDps))
                    problems.Add(Format("gyro {0:0.0} deg/s > {1:0}", q.GyroRmsDps, CalibrationLimits.GyroRmsDps));
                text.Add(Format("spread {0:0.0}/{1:0} deg", q.OrientationSpreadDegrees, CalibrationLimits.OrientationSpreadDegrees));
                if (!(q.OrientationSpreadDegrees <= CalibrationLimits.OrientationSpreadDegrees))
                    problems.Add(Format("spread {0:0.0} deg > {1:0}", q.OrientationSpreadDegrees, CalibrationLimits.OrientationSpreadDegrees));
                if (step != CalibrationStep.HeadingReset)
                {
                    text.Add(Format("|a|-g {0:0.00}/{1:0.0} m/s2", q.AccelerationNormError, CalibrationLimits.AccelerationNormError));
                    if (!(q.AccelerationNormError <= CalibrationLimits.AccelerationNormError))
                        problems.Add(Format("|a|-g {0:0.00} m/s2 > {1:0.0}", q.AccelerationNormError, CalibrationLimits.AccelerationNormError));
                }
                if (step == CalibrationStep.Heading)
                {
                    text.Add(Format("tilt {0:0}/{1:0} deg", q.TiltDegrees, CalibrationLimits.TiltDegrees));
                    if (!(q.TiltDegrees <= CalibrationLimits.TiltDegrees))
                        problems.Add(Format("tilt {0:0} deg > {1:0}: lay it flat", q.TiltDegrees, CalibrationLimits.TiltDegrees));
                }
                text.Add(q.Samples.ToString(Invariant) + " samples");
            }
            // The engine also refuses for checks it does not report as numbers (too few fresh
            // samples, T-pose without heading): say so rather than show a failing sensor as fine.
            if (!q.IsOk && !q.IsLeftOut && problems.Count == 0) problems.Add("refused by the engine (see the reason)");
            return new SensorQualitySummary(segment, q, Stillness(q), string.Join(", ", text), problems);
        }

        static float Ratio(float value, float limit)
        {
            if (float.IsNaN(value)) return 1f;
            return value <= 0 ? 0f : value / limit;
        }

        static string Format(string format, float a, float b) => string.Format(Invariant, format, a, b);
    }

    /// <summary>
    /// One display line per sensor of a calibration report ("left wrist: ok - gyro 0.4/10 deg/s,
    /// ..."), kept until the numbers it shows change. A run-time overlay redraws every frame;
    /// with this it builds strings only while a step is collecting, not while a result sits on
    /// screen.
    /// </summary>
    public sealed class CalibrationReportLines
    {
        struct Shown
        {
            public string Line;
            public MocapSegment Segment;
            public CalibrationStep Step;
            public bool Finished;
            public SensorQuality Quality;
        }

        readonly Shown[] _shown = new Shown[MocapSession.MaxSensors];

        /// <summary>The line for sensor <paramref name="index"/> (the session's order) of <paramref name="report"/>.</summary>
        public string GetLine(in CalibrationReport report, int index)
        {
            var quality = report.GetSensor(index);       // checks the range
            var segment = quality.Segment;
            ref var shown = ref _shown[index];
            if (shown.Line != null && shown.Segment == segment && shown.Step == report.Step
                && shown.Finished == report.IsFinished && SameNumbers(shown.Quality, quality))
                return shown.Line;
            var summary = CalibrationQuality.Summarize(report.Step, segment, quality);
            string verdict = !report.IsFinished ? "" : quality.IsLeftOut ? ": left out" : quality.IsOk ? ": ok" : ": REFUSED";
            shown.Line = CalibrationQuality.SensorName(segment) + verdict + " - " + summary.Text;
            shown.Segment = segment;
            shown.Step = report.Step;
            shown.Finished = report.IsFinished;
            shown.Quality = quality;
            return shown.Line;
        }

        /// <summary>The line for the sensor on <paramref name="segment"/>; throws when the report has none.</summary>
        public string GetLine(in CalibrationReport report, MocapSegment segment)
        {
            int index = report.IndexOf(segment);
            if (index < 0)
                throw new ArgumentException($"the report has no sensor on {CalibrationQuality.SensorName(segment)}", nameof(segment));
            return GetLine(report, index);
        }

        static bool SameNumbers(in SensorQuality a, in SensorQuality b) =>
            Same(a.GyroRmsDps, b.GyroRmsDps) && Same(a.OrientationSpreadDegrees, b.OrientationSpreadDegrees)
            && Same(a.AccelerationNormError, b.AccelerationNormError) && Same(a.TiltDegrees, b.TiltDegrees)
            && a.Samples == b.Samples && a.IsOk == b.IsOk && a.IsLeftOut == b.IsLeftOut;

        // NaN (a sensor the engine could not measure) shows as NaN each time: equal for display.
        static bool Same(float a, float b) => a == b || (float.IsNaN(a) && float.IsNaN(b));
    }
}
