// Pose recordings as JSON lines: the format `mocapctl replay --model M --json POSES.jsonl` writes,
// one object per solved pose:
//   {"sequence":0,"frame_sequence":450,"time_s":8.5,"flags":7,"root_position":[x,y,z],
//    "root_velocity":[x,y,z],"foot_contact":[l,r],"joint_rotations":[[w,x,y,z] x24],
//    "joint_positions":[[x,y,z] x24]}
// Optional "character" is read when present (and written by Save). Unknown keys are skipped, so
// a later engine may add fields without breaking this reader.

using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Text;
using Mocap.Imu.Maths;

namespace Mocap.Imu.Recording
{
    /// <summary>Reads and writes the JSON-lines pose format of <c>mocapctl replay --json</c>.</summary>
    public static class PoseJsonLines
    {
        /// <summary>Read every pose of a file (blank lines and lines starting with '#' skipped).</summary>
        /// <exception cref="MocapException">NotFound, Permission or IO naming the file and the cause; Format naming the file, line and problem.</exception>
        public static MocapPose[] Load(string path)
        {
            string[] lines = RecordingFiles.ReadAllLines(path, "pose JSON");
            var poses = new List<MocapPose>(lines.Length);
            for (int i = 0; i < lines.Length; i++)
            {
                string line = lines[i].Trim();
                if (line.Length == 0 || line[0] == '#') continue;
                try
                {
                    var pose = default(MocapPose);
                    Fill(new JsonReader(line).ReadObject(), ref pose);
                    poses.Add(pose);
                }
                catch (FormatException e)
                {
                    throw new MocapException(MocapStatus.Format, $"{path} line {i + 1}: {e.Message}", e);
                }
            }
            return poses.ToArray();
        }

        /// <summary>
        /// Write poses in the same format (numbers with the precision mocapctl prints, plus
        /// "character"), replacing <paramref name="path"/> only once every pose was written.
        /// </summary>
        /// <exception cref="MocapException">InvalidArgument for a pose holding NaN or infinity (which
        /// <see cref="Load"/> would refuse); NotFound, Permission or IO when the file cannot be
        /// written. The previous file is then unchanged.</exception>
        public static void Save(string path, ReadOnlySpan<MocapPose> poses)
        {
            // A span cannot enter a lambda: the writer walks an array.
            var all = poses.ToArray();
            RecordingFiles.WriteReplacing(path, "pose JSON", stream =>
            {
                // Not disposed: closing the stream is WriteReplacing's (and a failed flush here
                // must not hide the exception that stopped the writing).
                var writer = new StreamWriter(stream, new UTF8Encoding(false), 1 << 16) { NewLine = "\n" };
                var text = new StringBuilder();
                for (int i = 0; i < all.Length; i++)
                {
                    string field = PoseRecording.FirstNonFinite(all[i]);
                    if (field != null)
                        throw new MocapException(MocapStatus.InvalidArgument,
                            $"pose JSON {path}: pose {i}: {field} is not finite; nothing was written");
                    text.Clear();
                    AppendLine(text, all[i]);
                    writer.Write(text);
                }
                writer.Flush();
            });
        }

        static void AppendLine(StringBuilder text, in MocapPose p)
        {
            text.Append("{\"sequence\":").Append(p.Sequence.ToString(CultureInfo.InvariantCulture))
                .Append(",\"frame_sequence\":").Append(p.FrameSequence.ToString(CultureInfo.InvariantCulture))
                .Append(",\"time_s\":").Append(F(p.TimeSeconds, "F6"))
                .Append(",\"character\":").Append(p.Character.ToString(CultureInfo.InvariantCulture))
                .Append(",\"flags\":").Append(((uint)p.Flags).ToString(CultureInfo.InvariantCulture));
            AppendVec(text, "root_position", p.RootPosition);
            AppendVec(text, "root_velocity", p.RootVelocity);
            text.Append(",\"foot_contact\":[").Append(F(p.LeftFootContact, "F4")).Append(',')
                .Append(F(p.RightFootContact, "F4")).Append("],\"joint_rotations\":[");
            for (int j = 0; j < MocapPose.JointCount; j++)
            {
                Quat q = p.GetJointRotation(j);
                text.Append(j > 0 ? ",[" : "[").Append(F(q.W, "F6")).Append(',').Append(F(q.X, "F6"))
                    .Append(',').Append(F(q.Y, "F6")).Append(',').Append(F(q.Z, "F6")).Append(']');
            }
            text.Append("],\"joint_positions\":[");
            for (int j = 0; j < MocapPose.JointCount; j++)
            {
                Vec3 v = p.GetJointPosition(j);
                text.Append(j > 0 ? ",[" : "[").Append(F(v.X, "F6")).Append(',').Append(F(v.Y, "F6"))
                    .Append(',').Append(F(v.Z, "F6")).Append(']');
            }
            text.Append("]}\n");
        }

        static void AppendVec(StringBuilder text, string key, Vec3 v) =>
            text.Append(",\"").Append(key).Append("\":[").Append(F(v.X, "F6")).Append(',')
                .Append(F(v.Y, "F6")).Append(',').Append(F(v.Z, "F6")).Append(']');

        static string F(double value, string format) => value.ToString(format, CultureInfo.InvariantCulture);

        static void Fill(Dictionary<string, object> o, ref MocapPose pose)
        {
            pose.Sequence = (ulong)Integer(o, "sequence");
            pose.FrameSequence = (ulong)Integer(o, "frame_sequence");
            pose.TimeSeconds = Number(o, "time_s");
            pose.Flags = (MocapPoseFlags)(uint)Integer(o, "flags", uint.MaxValue);
            if (o.ContainsKey("character")) pose.Character = (int)Integer(o, "character", int.MaxValue);
            pose.RootPosition = Vector(Array(o, "root_position", 3), "root_position");
            pose.RootVelocity = Vector(Array(o, "root_velocity", 3), "root_velocity");
            var contact = Array(o, "foot_contact", 2);
            pose.LeftFootContact = Element(contact, 0, "foot_contact");
            pose.RightFootContact = Element(contact, 1, "foot_contact");
            var rotations = Array(o, "joint_rotations", MocapPose.JointCount);
            var positions = Array(o, "joint_positions", MocapPose.JointCount);
            for (int j = 0; j < MocapPose.JointCount; j++)
            {
                string where = $"joint_rotations[{j}]";
                if (!(rotations[j] is List<object> q) || q.Count != 4)
                    throw new FormatException($"{where} is not an array of 4 numbers (w, x, y, z)");
                pose.SetJointRotation(j, Quat.FromWxyz(Element(q, 0, where), Element(q, 1, where),
                                                       Element(q, 2, where), Element(q, 3, where)));
                where = $"joint_positions[{j}]";
                if (!(positions[j] is List<object> v) || v.Count != 3)
                    throw new FormatException($"{where} is not an array of 3 numbers");
                pose.SetJointPosition(j, Vector(v, where));
            }
        }

        static double Number(Dictionary<string, object> o, string key)
        {
            if (!o.TryGetValue(key, out var value)) throw new FormatException($"\"{key}\" is missing");
            if (!(value is double d)) throw new FormatException($"\"{key}\" is not a number");
            if (double.IsInfinity(d)) throw new FormatException($"\"{key}\" is not a finite number");
            return d;
        }

        // A whole number from 0 to max (at most 2^53, where doubles stop holding every integer):
        // flags and character have narrower fields, and a larger value must not wrap around.
        static long Integer(Dictionary<string, object> o, string key, long max = 1L << 53)
        {
            double d = Number(o, key);
            if (d < 0 || d != Math.Floor(d) || d > 9007199254740992.0)
                throw new FormatException($"\"{key}\" is {d.ToString("R", CultureInfo.InvariantCulture)}, not a non-negative integer");
            if (d > max)
                throw new FormatException($"\"{key}\" is {d.ToString("R", CultureInfo.InvariantCulture)}, more than its largest value {max}");
            return (long)d;
        }

        static List<object> Array(Dictionary<string, object> o, string key, int count)
        {
            if (!o.TryGetValue(key, out var value)) throw new FormatException($"\"{key}\" is missing");
            if (!(value is List<object> list) || list.Count != count)
                throw new FormatException($"\"{key}\" is not an array of {count} items");
            return list;
        }

        // Pose values are floats: a number beyond float range (1e39, 1e999) would become infinity.
        static float Element(List<object> list, int i, string where)
        {
            if (!(list[i] is double d)) throw new FormatException($"{where} item {i} is not a number");
            float f = (float)d;
            if (!float.IsFinite(f)) throw new FormatException($"{where} item {i} ({d}) is not a finite float");
            return f;
        }

        static Vec3 Vector(List<object> list, string where) =>
            new Vec3(Element(list, 0, where), Element(list, 1, where), Element(list, 2, where));

        /// <summary>
        /// A minimal JSON reader for one line: objects, arrays, numbers, strings, true/false/null.
        /// Enough for pose lines without pulling a JSON library into Unity's core assembly.
        /// </summary>
        sealed class JsonReader
        {
            readonly string _s;
            int _i;

            public JsonReader(string s) { _s = s; }

            public Dictionary<string, object> ReadObject()
            {
                SkipSpace();
                if (!(ReadValue() is Dictionary<string, object> o)) throw Error("expected a JSON object");
                SkipSpace();
                if (_i != _s.Length) throw Error("unexpected text after the object");
                return o;
            }

            object ReadValue()
            {
                SkipSpace();
                if (_i >= _s.Length) throw Error("unexpected end of line");
                char c = _s[_i];
                if (c == '{') return ReadObjectBody();
                if (c == '[') return ReadArray();
                if (c == '"') return ReadString();
                if (Match("true")) return true;
                if (Match("false")) return false;
                if (Match("null")) return null;
                return ReadNumber();
            }

            Dictionary<string, object> ReadObjectBody()
            {
                var o = new Dictionary<string, object>();
                _i++;
                SkipSpace();
                if (Peek() == '}') { _i++; return o; }
                for (;;)
                {
                    SkipSpace();
                    if (Peek() != '"') throw Error("expected a key");
                    string key = ReadString();
                    SkipSpace();
                    if (Peek() != ':') throw Error($"expected ':' after \"{key}\"");
                    _i++;
                    o[key] = ReadValue();
                    SkipSpace();
                    char c = Peek();
                    _i++;
                    if (c == '}') return o;
                    if (c != ',') throw Error("expected ',' or '}'", _i - 1);
                }
            }

            List<object> ReadArray()
            {
                var list = new List<object>();
                _i++;
                SkipSpace();
                if (Peek() == ']') { _i++; return list; }
                for (;;)
                {
                    list.Add(ReadValue());
                    SkipSpace();
                    char c = Peek();
                    _i++;
                    if (c == ']') return list;
                    if (c != ',') throw Error("expected ',' or ']'", _i - 1);
                }
            }

            string ReadString()
            {
                var text = new StringBuilder();
                _i++;
                while (_i < _s.Length && _s[_i] != '"')
                {
                    char c = _s[_i++];
                    if (c == '\\' && _i < _s.Length)
                    {
                        char e = _s[_i++];
                        if (e == 'u' && _i + 4 <= _s.Length)
                        {
                            text.Append((char)int.Parse(_s.Substring(_i, 4), NumberStyles.HexNumber, CultureInfo.InvariantCulture));
                            _i += 4;
                        }
                        else text.Append(e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e == 'b' ? '\b' : e == 'f' ? '\f' : e);
                    }
                    else text.Append(c);
                }
                if (_i >= _s.Length) throw Error("unterminated string");
                _i++;
                return text.ToString();
            }

            object ReadNumber()
            {
                int start = _i;
                while (_i < _s.Length && "+-0123456789.eE".IndexOf(_s[_i]) >= 0) _i++;
                if (_i == start ||
                    !double.TryParse(_s.Substring(start, _i - start), NumberStyles.Float, CultureInfo.InvariantCulture, out double d))
                    throw Error("expected a value", start);
                return d;
            }

            bool Match(string word)
            {
                if (string.CompareOrdinal(_s, _i, word, 0, word.Length) != 0) return false;
                _i += word.Length;
                return true;
            }

            char Peek() => _i < _s.Length ? _s[_i] : '\0';

            void SkipSpace()
            {
                while (_i < _s.Length && char.IsWhiteSpace(_s[_i])) _i++;
            }

            FormatException Error(string what, int at = -1) =>
                new FormatException($"{what} at column {(at < 0 ? _i : at) + 1}");
        }
    }
}
