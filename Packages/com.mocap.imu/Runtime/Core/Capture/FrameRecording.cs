// Pose recordings: the frame CSV that `mocapctl replay --csv` writes, one row per engine frame:
//   sequence,time_s,flags, then per segment (engine order) qw,qx,qy,qz,ax,ay,az,flags
// Loaded back into MocapFrames, a recording plays in the editor and in PlayMode tests exactly
// like frames drained from a live session (only the fields the CSV holds are filled).

using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Text;
using Mocap.Imu.Recording;

namespace Mocap.Imu.Capture
{
    /// <summary>Frames recorded as CSV (the format of <c>mocapctl replay --csv</c>).</summary>
    public static class FrameRecording
    {
        const int ColumnsPerSensor = 8;
        const int Columns = 3 + MocapSession.SensorCount * ColumnsPerSensor;

        /// <summary>
        /// Read every frame of a recording. Fills sequence, time, flags, fresh mask (from the
        /// sensors' Held flag), bone orientation, bone acceleration and sensor flags.
        /// </summary>
        /// <exception cref="MocapException">NotFound, Permission or IO naming the file and the cause;
        /// Format naming the file and line.</exception>
        public static MocapFrame[] Load(string path)
        {
            string[] lines = RecordingFiles.ReadAllLines(path, "frame recording");
            var frames = new List<MocapFrame>(lines.Length);
            for (int i = 0; i < lines.Length; i++)
            {
                string line = lines[i].Trim();
                if (line.Length == 0 || line[0] == '#' || line.StartsWith("sequence", StringComparison.Ordinal))
                    continue;
                frames.Add(ParseRow(line, path, i + 1));
            }
            return frames.ToArray();
        }

        /// <summary>
        /// Write frames in the same format (mocapctl's precision), replacing <paramref name="path"/>
        /// only once every frame was written.
        /// </summary>
        /// <exception cref="MocapException">InvalidArgument for a frame holding NaN or infinity (which
        /// <see cref="Load"/> would refuse); NotFound, Permission or IO when the file cannot be
        /// written. The previous file is then unchanged.</exception>
        public static void Save(string path, ReadOnlySpan<MocapFrame> frames)
        {
            // A span cannot enter a lambda: the writer walks an array.
            var all = frames.ToArray();
            RecordingFiles.WriteReplacing(path, "frame recording", stream =>
            {
                // Not disposed: closing the stream is WriteReplacing's (and a failed flush here
                // must not hide the exception that stopped the writing).
                var writer = new StreamWriter(stream, new UTF8Encoding(false), 1 << 16) { NewLine = "\n" };
                writer.Write("sequence,time_s,flags");
                for (int s = 0; s < MocapSession.SensorCount; s++)
                {
                    string n = SegmentNames[s];
                    writer.Write($",{n}_qw,{n}_qx,{n}_qy,{n}_qz,{n}_ax,{n}_ay,{n}_az,{n}_flags");
                }
                writer.WriteLine();
                var c = CultureInfo.InvariantCulture;
                for (int i = 0; i < all.Length; i++)
                {
                    ref readonly MocapFrame f = ref all[i];
                    string field = FirstNonFinite(f);
                    if (field != null)
                        throw new MocapException(MocapStatus.InvalidArgument,
                            $"frame recording {path}: frame {i}: {field} is not finite; nothing was written");
                    writer.Write(string.Format(c, "{0},{1:F6},{2}", f.Sequence, f.TimeSeconds, (uint)f.Flags));
                    for (int s = 0; s < MocapSession.SensorCount; s++)
                    {
                        var sf = f.GetSensor((MocapSegment)s);
                        var q = sf.BoneOrientation;
                        var a = sf.BoneAcceleration;
                        writer.Write(string.Format(c, ",{0:F6},{1:F6},{2:F6},{3:F6},{4:F4},{5:F4},{6:F4},{7}",
                            q.W, q.X, q.Y, q.Z, a.X, a.Y, a.Z, (uint)sf.Flags));
                    }
                    writer.WriteLine();
                }
                writer.Flush();
            });
        }

        // The values the CSV holds that Load requires finite; null when all are.
        static string FirstNonFinite(in MocapFrame frame)
        {
            if (!double.IsFinite(frame.TimeSeconds)) return "time";
            for (int s = 0; s < MocapSession.SensorCount; s++)
            {
                var sensor = frame.GetSensor((MocapSegment)s);
                var q = sensor.BoneOrientation;
                var a = sensor.BoneAcceleration;
                if (!float.IsFinite(q.W) || !float.IsFinite(q.X) || !float.IsFinite(q.Y) || !float.IsFinite(q.Z))
                    return SegmentNames[s] + " orientation";
                if (!float.IsFinite(a.X) || !float.IsFinite(a.Y) || !float.IsFinite(a.Z))
                    return SegmentNames[s] + " acceleration";
            }
            return null;
        }

        // The engine's segment names (mocap_segment_name), kept here so recordings need no engine.
        static readonly string[] SegmentNames =
            { "pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head" };

        static MocapFrame ParseRow(string line, string path, int lineNumber)
        {
            var cells = line.Split(',');
            if (cells.Length != Columns)
                throw new MocapException(MocapStatus.Format,
                    $"frame recording {path}:{lineNumber}: {cells.Length} columns, expected {Columns}");
            var frame = new MocapFrame
            {
                Sequence = Unsigned(cells[0], path, lineNumber),
                TimeSeconds = Double(cells[1], path, lineNumber),
                Flags = (MocapFrameFlags)(uint)Unsigned(cells[2], path, lineNumber, uint.MaxValue),
            };
            for (int s = 0; s < MocapSession.SensorCount; s++)
            {
                int c = 3 + s * ColumnsPerSensor;
                var sensor = new MocapSensorFrame
                {
                    BoneOrientation = new MocapQuaternion(Number(cells[c], path, lineNumber),
                        Number(cells[c + 1], path, lineNumber), Number(cells[c + 2], path, lineNumber),
                        Number(cells[c + 3], path, lineNumber)),
                    BoneAcceleration = new MocapVector3(Number(cells[c + 4], path, lineNumber),
                        Number(cells[c + 5], path, lineNumber), Number(cells[c + 6], path, lineNumber)),
                    Flags = (MocapSensorFlags)(uint)Unsigned(cells[c + 7], path, lineNumber, uint.MaxValue),
                };
                // The CSV has no fresh mask; a valid sensor that is not held was fresh.
                if ((sensor.Flags & (MocapSensorFlags.Valid | MocapSensorFlags.Held)) == MocapSensorFlags.Valid)
                    frame.FreshMask |= 1u << s;
                frame.SetSensor((MocapSegment)s, sensor);
            }
            return frame;
        }

        static ulong Unsigned(string text, string path, int lineNumber, ulong max = ulong.MaxValue)
        {
            if (!ulong.TryParse(text, NumberStyles.None, CultureInfo.InvariantCulture, out ulong value) || value > max)
                throw new MocapException(MocapStatus.Format,
                    $"frame recording {path}:{lineNumber}: '{text}' is not a whole number from 0 to {max}");
            return value;
        }

        static float Number(string text, string path, int lineNumber)
        {
            // Finite as a double is not enough: 1e39 becomes float infinity.
            float value = (float)Double(text, path, lineNumber);
            if (!float.IsFinite(value))
                throw new MocapException(MocapStatus.Format,
                    $"frame recording {path}:{lineNumber}: '{text}' is beyond float range");
            return value;
        }

        static double Double(string text, string path, int lineNumber)
        {
            if (!double.TryParse(text, NumberStyles.Float, CultureInfo.InvariantCulture, out double value) ||
                double.IsNaN(value) || double.IsInfinity(value))
                throw new MocapException(MocapStatus.Format,
                    $"frame recording {path}:{lineNumber}: '{text}' is not a finite number");
            return value;
        }
    }
}
