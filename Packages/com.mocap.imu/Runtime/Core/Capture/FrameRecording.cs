// Frame recordings: the frame CSV that `mocapctl replay --csv` writes, one row per engine frame:
//   sequence,time_s,flags, then per sensor (the session's config order) qw,qx,qy,qz,ax,ay,az,flags
// The header row names each sensor's columns after its segment ("chest_qw"), so the header gives
// the sensor set. Version 2 files start with "# mocap frame recording 2" and must have the
// header; a file without the version line is version 1, whose rows without a header hold the
// six segments pelvis .. head in that order.
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
        /// <summary>The format version <see cref="Save"/> writes.</summary>
        public const int Version = 2;

        const string VersionPrefix = "# mocap frame recording ";
        const int ColumnsPerSensor = 8;
        static readonly string[] SensorColumns = { "qw", "qx", "qy", "qz", "ax", "ay", "az", "flags" };

        // Version 1 files have no version line and always carried these six, in this order.
        static readonly MocapSegment[] VersionOneSegments =
        {
            MocapSegment.Pelvis, MocapSegment.LeftWrist, MocapSegment.RightWrist,
            MocapSegment.LeftShin, MocapSegment.RightShin, MocapSegment.Head,
        };

        /// <summary>
        /// Read every frame of a recording (version 1 or 2). Fills sequence, time, flags, sensor
        /// count, and per sensor its segment, bone orientation, bone acceleration, flags, the
        /// fresh mask and a state derived from the flags.
        /// </summary>
        /// <exception cref="MocapException">NotFound, Permission or IO naming the file and the cause;
        /// Format naming the file and line.</exception>
        public static MocapFrame[] Load(string path)
        {
            string[] lines = RecordingFiles.ReadAllLines(path, "frame recording");
            var frames = new List<MocapFrame>(lines.Length);
            int version = 1;
            MocapSegment[] segments = null;
            for (int i = 0; i < lines.Length; i++)
            {
                string line = lines[i].Trim();
                if (line.Length == 0) continue;
                if (line.StartsWith(VersionPrefix, StringComparison.Ordinal))
                {
                    if (frames.Count > 0 || segments != null)
                        throw Error(path, i + 1, "the version line must come before the header and the rows");
                    version = ParseVersion(line.Substring(VersionPrefix.Length), path, i + 1);
                    continue;
                }
                if (line[0] == '#') continue;
                if (line.StartsWith("sequence", StringComparison.Ordinal))
                {
                    if (frames.Count > 0 || segments != null)
                        throw Error(path, i + 1, "a second header, or a header after the rows");
                    segments = ParseHeader(line, path, i + 1);
                    continue;
                }
                if (segments == null)
                {
                    if (version != 1) throw Error(path, i + 1, "a row before the header (version 2 files name their sensors there)");
                    segments = VersionOneSegments;
                }
                frames.Add(ParseRow(line, segments, path, i + 1));
            }
            return frames.ToArray();
        }

        /// <summary>
        /// Write frames in the current format (mocapctl's precision), replacing <paramref name="path"/>
        /// only once every frame was written. Every frame must have the first frame's sensors.
        /// </summary>
        /// <exception cref="MocapException">InvalidArgument for a frame holding NaN or infinity (which
        /// <see cref="Load"/> would refuse) or other sensors than the first frame; NotFound,
        /// Permission or IO when the file cannot be written. The previous file is then unchanged.</exception>
        public static void Save(string path, ReadOnlySpan<MocapFrame> frames)
        {
            // A span cannot enter a lambda: the writer walks an array.
            var all = frames.ToArray();
            var segments = new MocapSegment[all.Length > 0 ? all[0].SensorCount : 0];
            for (int s = 0; s < segments.Length; s++) segments[s] = all[0].GetSensor(s).Segment;
            for (int i = 0; i < all.Length; i++)
            {
                string problem = SensorSetDiffers(all[i], segments);
                if (problem != null)
                    throw new MocapException(MocapStatus.InvalidArgument,
                        $"frame recording {path}: frame {i}: {problem}; nothing was written");
                string field = FirstNonFinite(all[i]);
                if (field != null)
                    throw new MocapException(MocapStatus.InvalidArgument,
                        $"frame recording {path}: frame {i}: {field} is not finite; nothing was written");
            }
            RecordingFiles.WriteReplacing(path, "frame recording", stream =>
            {
                // Not disposed: closing the stream is WriteReplacing's (and a failed flush here
                // must not hide the exception that stopped the writing).
                var writer = new StreamWriter(stream, new UTF8Encoding(false), 1 << 16) { NewLine = "\n" };
                writer.WriteLine(VersionPrefix + Version.ToString(CultureInfo.InvariantCulture));
                writer.Write("sequence,time_s,flags");
                foreach (var segment in segments)
                {
                    string n = SegmentTable.SnakeName(segment);
                    foreach (var column in SensorColumns) writer.Write($",{n}_{column}");
                }
                writer.WriteLine();
                var c = CultureInfo.InvariantCulture;
                for (int i = 0; i < all.Length; i++)
                {
                    ref readonly MocapFrame f = ref all[i];
                    writer.Write(string.Format(c, "{0},{1:F6},{2}", f.Sequence, f.TimeSeconds, (uint)f.Flags));
                    for (int s = 0; s < segments.Length; s++)
                    {
                        var sf = f.GetSensor(s);
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

        static string SensorSetDiffers(in MocapFrame frame, MocapSegment[] segments)
        {
            if (frame.SensorCount != segments.Length)
                return $"{frame.SensorCount} sensors, the first frame has {segments.Length}";
            for (int s = 0; s < segments.Length; s++)
                if (frame.GetSensor(s).Segment != segments[s])
                    return $"sensor {s} is on {SegmentTable.SnakeName(frame.GetSensor(s).Segment)}, " +
                           $"in the first frame on {SegmentTable.SnakeName(segments[s])}";
            return null;
        }

        // The values the CSV holds that Load requires finite; null when all are.
        static string FirstNonFinite(in MocapFrame frame)
        {
            if (!double.IsFinite(frame.TimeSeconds)) return "time";
            for (int s = 0; s < frame.SensorCount; s++)
            {
                var sensor = frame.GetSensor(s);
                var q = sensor.BoneOrientation;
                var a = sensor.BoneAcceleration;
                if (!float.IsFinite(q.W) || !float.IsFinite(q.X) || !float.IsFinite(q.Y) || !float.IsFinite(q.Z))
                    return SegmentTable.SnakeName(sensor.Segment) + " orientation";
                if (!float.IsFinite(a.X) || !float.IsFinite(a.Y) || !float.IsFinite(a.Z))
                    return SegmentTable.SnakeName(sensor.Segment) + " acceleration";
            }
            return null;
        }

        static int ParseVersion(string text, string path, int lineNumber)
        {
            if (!int.TryParse(text.Trim(), NumberStyles.None, CultureInfo.InvariantCulture, out int version) || version < 1)
                throw Error(path, lineNumber, $"'{text.Trim()}' is not a format version");
            if (version > Version)
                throw Error(path, lineNumber, $"format version {version}; this reader knows versions 1 to {Version}");
            return version;
        }

        // The sensor set from the column names: "<segment>_qw" ... "<segment>_flags" per sensor.
        static MocapSegment[] ParseHeader(string line, string path, int lineNumber)
        {
            var cells = line.Split(',');
            if (cells.Length < 3 || cells[0] != "sequence" || cells[1] != "time_s" || cells[2] != "flags")
                throw Error(path, lineNumber, "the header does not start with sequence,time_s,flags");
            if ((cells.Length - 3) % ColumnsPerSensor != 0)
                throw Error(path, lineNumber, $"{cells.Length} columns: not 3 plus {ColumnsPerSensor} per sensor");
            int count = (cells.Length - 3) / ColumnsPerSensor;
            if (count > MocapSession.MaxSensors)
                throw Error(path, lineNumber, $"{count} sensors; a frame holds at most {MocapSession.MaxSensors}");
            var segments = new MocapSegment[count];
            for (int s = 0; s < count; s++)
            {
                string first = cells[3 + s * ColumnsPerSensor];
                string name = first.EndsWith("_qw", StringComparison.Ordinal) ? first.Substring(0, first.Length - 3) : null;
                if (name == null || !SegmentTable.TryParseSnakeName(name, out segments[s]))
                    throw Error(path, lineNumber, $"column '{first}' does not name a body segment's qw");
                for (int k = 0; k < ColumnsPerSensor; k++)
                    if (cells[3 + s * ColumnsPerSensor + k] != name + "_" + SensorColumns[k])
                        throw Error(path, lineNumber,
                            $"column '{cells[3 + s * ColumnsPerSensor + k]}', expected '{name}_{SensorColumns[k]}'");
                if (Array.IndexOf(segments, segments[s], 0, s) >= 0)
                    throw Error(path, lineNumber, $"sensor {name} appears twice");
            }
            return segments;
        }

        static MocapFrame ParseRow(string line, MocapSegment[] segments, string path, int lineNumber)
        {
            var cells = line.Split(',');
            int columns = 3 + segments.Length * ColumnsPerSensor;
            if (cells.Length != columns)
                throw Error(path, lineNumber, $"{cells.Length} columns, expected {columns}");
            var frame = new MocapFrame
            {
                Sequence = Unsigned(cells[0], path, lineNumber),
                TimeSeconds = Double(cells[1], path, lineNumber),
                Flags = (MocapFrameFlags)(uint)Unsigned(cells[2], path, lineNumber, uint.MaxValue),
                SensorCount = segments.Length,
            };
            for (int s = 0; s < segments.Length; s++)
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
                    Segment = segments[s],
                };
                sensor.State = StateFromFlags(sensor.Flags);
                // The CSV has no fresh mask; a valid sensor that is not held was fresh.
                if (sensor.State == MocapSensorState.Fresh) frame.FreshMask |= 1u << s;
                frame.SetSensor(s, sensor);
            }
            return frame;
        }

        // The CSV keeps the flags only; they say the same as the state in bits.
        static MocapSensorState StateFromFlags(MocapSensorFlags flags)
        {
            if ((flags & MocapSensorFlags.Valid) == 0) return MocapSensorState.Absent;
            if ((flags & MocapSensorFlags.Stale) != 0) return MocapSensorState.Silent;
            if ((flags & MocapSensorFlags.Held) != 0) return MocapSensorState.Holding;
            return MocapSensorState.Fresh;
        }

        static MocapException Error(string path, int lineNumber, string what) =>
            new MocapException(MocapStatus.Format, $"frame recording {path}:{lineNumber}: {what}");

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
