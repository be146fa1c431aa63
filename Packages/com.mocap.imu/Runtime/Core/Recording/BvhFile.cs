// A general BVH (Biovision hierarchy) reader: any hierarchy, any number of roots, any channel
// count and order per joint, End Sites. It reads the engine's pose BVH (`mocapctl replay --out
// X.bvh`, Native~/src/output/bvh_writer.c) and is deliberately written from the format, not from that
// writer, so the two check each other (issue 7 asks for two independent implementations).
//
// Conventions (those of the engine, Blender and training/bvh.py):
//  - rotation channels are Euler angles in degrees, intrinsic in the listed order: for
//    "Zrotation Xrotation Yrotation" the joint's rotation is R = Rz * Rx * Ry, mapping the joint
//    frame into its parent's; right-handed rotations (Rx(a) turns +Y towards +Z);
//  - position channels are the joint's translation in its parent frame and replace the OFFSET
//    components they name (absolute, as the engine writes the root); a joint without position
//    channels is translated by its OFFSET.

using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using Mocap.Imu.Maths;
using Mocap.Imu.Skeleton;

namespace Mocap.Imu.Recording
{
    /// <summary>One BVH channel.</summary>
    public enum BvhChannel
    {
        Xposition,
        Yposition,
        Zposition,
        Xrotation,
        Yrotation,
        Zrotation,
    }

    /// <summary>One joint of a BVH hierarchy.</summary>
    public sealed class BvhJoint
    {
        internal BvhJoint(string name, int parent, Vec3 offset, BvhChannel[] channels, int firstChannel)
        {
            Name = name;
            Parent = parent;
            Offset = offset;
            Channels = channels;
            FirstChannel = firstChannel;
        }

        /// <summary>Joint name as written.</summary>
        public string Name { get; }
        /// <summary>Index of the parent joint, -1 for a root.</summary>
        public int Parent { get; }
        /// <summary>OFFSET: the rest translation in the parent frame.</summary>
        public Vec3 Offset { get; }
        /// <summary>The joint's channels in file order.</summary>
        public IReadOnlyList<BvhChannel> Channels { get; }
        /// <summary>Column of the joint's first channel in a MOTION line.</summary>
        public int FirstChannel { get; }
        /// <summary>The End Site offset of a leaf, or null.</summary>
        public Vec3? EndSite { get; internal set; }
    }

    /// <summary>A parsed BVH file: hierarchy and motion.</summary>
    public sealed class BvhFile
    {
        readonly List<BvhJoint> _joints;
        readonly float[] _motion;

        BvhFile(List<BvhJoint> joints, int channels, int frames, double frameTime, float[] motion)
        {
            _joints = joints;
            ChannelCount = channels;
            FrameCount = frames;
            FrameTime = frameTime;
            _motion = motion;
        }

        /// <summary>Joints in file order (depth first): a parent always precedes its children.</summary>
        public IReadOnlyList<BvhJoint> Joints => _joints;
        /// <summary>Channels per frame.</summary>
        public int ChannelCount { get; }
        /// <summary>Frames of motion.</summary>
        public int FrameCount { get; }
        /// <summary>Seconds per frame.</summary>
        public double FrameTime { get; }
        /// <summary>
        /// Motion lines after the frames the header counts, left out: a writer stopped between
        /// appending frames and updating <c>Frames:</c> (a crash while streaming). 0 normally.
        /// </summary>
        public int IgnoredTrailingLines { get; private set; }

        /// <summary>Read a BVH file.</summary>
        /// <exception cref="MocapException">NotFound, Permission or IO naming the file and the cause; Format naming the file, line and problem.</exception>
        public static BvhFile Load(string path) => Parse(RecordingFiles.ReadAllLines(path, "BVH"), path);

        /// <summary>Parse BVH text; <paramref name="source"/> names it in errors.</summary>
        public static BvhFile Parse(string text, string source = "BVH text")
        {
            if (text == null) throw new ArgumentNullException(nameof(text));
            return Parse(text.Replace("\r\n", "\n").Split('\n'), source);
        }

        /// <summary>Index of the joint called <paramref name="name"/>, or -1.</summary>
        public int IndexOf(string name) => _joints.FindIndex(j => j.Name == name);

        /// <summary>The value of one channel column in one frame.</summary>
        public float GetChannel(int frame, int channel)
        {
            CheckFrame(frame);
            if ((uint)channel >= (uint)ChannelCount) throw new ArgumentOutOfRangeException(nameof(channel));
            return _motion[frame * ChannelCount + channel];
        }

        /// <summary>A joint's rotation in its parent frame at <paramref name="frame"/> (identity without rotation channels).</summary>
        public Quat GetLocalRotation(int frame, int joint)
        {
            CheckFrame(frame);
            var j = _joints[joint];
            Quat q = Quat.Identity;
            int row = frame * ChannelCount + j.FirstChannel;
            for (int c = 0; c < j.Channels.Count; c++)
            {
                // Intrinsic order: each later rotation is applied in the frame the earlier ones made,
                // i.e. multiplied on the right.
                var axis = j.Channels[c];
                if (axis < BvhChannel.Xrotation) continue;
                float radians = _motion[row + c] * (float)(Math.PI / 180.0);
                Vec3 unit = axis == BvhChannel.Xrotation ? Vec3.UnitX : axis == BvhChannel.Yrotation ? Vec3.UnitY : Vec3.UnitZ;
                q = q * Quat.AxisAngle(unit, radians);
            }
            return q.Normalized;
        }

        /// <summary>A joint's translation in its parent frame at <paramref name="frame"/>: its OFFSET with position channels substituted.</summary>
        public Vec3 GetLocalTranslation(int frame, int joint)
        {
            CheckFrame(frame);
            var j = _joints[joint];
            float x = j.Offset.X, y = j.Offset.Y, z = j.Offset.Z;
            int row = frame * ChannelCount + j.FirstChannel;
            for (int c = 0; c < j.Channels.Count; c++)
            {
                switch (j.Channels[c])
                {
                    case BvhChannel.Xposition: x = _motion[row + c]; break;
                    case BvhChannel.Yposition: y = _motion[row + c]; break;
                    case BvhChannel.Zposition: z = _motion[row + c]; break;
                }
            }
            return new Vec3(x, y, z);
        }

        /// <summary>Global rotation and position of every joint at <paramref name="frame"/>. Allocates nothing.</summary>
        public void ForwardKinematics(int frame, Span<Quat> globalRotations, Span<Vec3> positions)
        {
            if (globalRotations.Length < _joints.Count || positions.Length < _joints.Count)
                throw new ArgumentException($"forward kinematics needs spans of {_joints.Count} joints");
            for (int j = 0; j < _joints.Count; j++)
            {
                int p = _joints[j].Parent;
                Quat local = GetLocalRotation(frame, j);
                Vec3 t = GetLocalTranslation(frame, j);
                globalRotations[j] = p < 0 ? local : (globalRotations[p] * local).Normalized;
                positions[j] = p < 0 ? t : positions[p] + globalRotations[p] * t;
            }
        }

        /// <summary>
        /// The joint index of each SMPL-24 joint (by contract name), for <see cref="ToSmplPose"/>.
        /// </summary>
        /// <exception cref="MocapException">Format: a contract joint is missing.</exception>
        public int[] SmplJointMap()
        {
            var map = new int[SmplSkeleton.JointCount];
            for (int j = 0; j < map.Length; j++)
            {
                map[j] = IndexOf(SmplSkeleton.NameOf(j));
                if (map[j] < 0)
                    throw new MocapException(MocapStatus.Format, $"the BVH has no joint '{SmplSkeleton.NameOf(j)}' (SMPL-24 joint {j})");
            }
            return map;
        }

        /// <summary>
        /// One frame as an <see cref="SmplPose"/>: the mapped joints' local rotations (the root's
        /// is global) and the root's translation as the pelvis position. Expects a skeleton whose
        /// rest pose is the model's T-pose, as the engine writes. Allocates nothing.
        /// </summary>
        public void ToSmplPose(int frame, int[] smplJointMap, SmplPose pose)
        {
            if (smplJointMap == null || smplJointMap.Length != SmplSkeleton.JointCount)
                throw new ArgumentException("use SmplJointMap()", nameof(smplJointMap));
            if (pose == null) throw new ArgumentNullException(nameof(pose));
            for (int j = 0; j < SmplSkeleton.JointCount; j++)
                pose.Rotations[j] = GetLocalRotation(frame, smplJointMap[j]);
            pose.RootPosition = GetLocalTranslation(frame, smplJointMap[0]);
        }

        /// <summary>The SMPL-24 skeleton of the mapped joints' OFFSETs (joint 0: the root OFFSET, its rest position).</summary>
        public SmplSkeleton ToSmplSkeleton(int[] smplJointMap)
        {
            var offsets = new Vec3[SmplSkeleton.JointCount];
            for (int j = 0; j < offsets.Length; j++) offsets[j] = _joints[smplJointMap[j]].Offset;
            return SmplSkeleton.FromRestOffsets(offsets);
        }

        void CheckFrame(int frame)
        {
            if ((uint)frame >= (uint)FrameCount)
                throw new ArgumentOutOfRangeException(nameof(frame), frame, $"the BVH has {FrameCount} frames");
        }

        // ------------------------------------------------------------------------------------
        // Parsing

        static BvhFile Parse(string[] lines, string source)
        {
            var tokens = new Tokens(lines, source);
            var joints = new List<BvhJoint>();
            tokens.Expect("HIERARCHY");
            int channels = 0;
            while (tokens.PeekIs("ROOT"))
            {
                tokens.Next();
                ParseJoint(tokens, joints, -1, ref channels);
            }
            if (joints.Count == 0) throw tokens.Error("expected ROOT");
            tokens.Expect("MOTION");
            tokens.Expect("Frames:");
            int frames = tokens.NextInt("frame count");
            tokens.Expect("Frame");
            tokens.Expect("Time:");
            double frameTime = tokens.NextDouble("frame time");
            if (!(frameTime > 0) || double.IsInfinity(frameTime)) throw tokens.Error($"frame time {frameTime} must be positive");

            // Motion: one line per frame, exactly `channels` numbers each. The header's count is
            // not trusted for the allocation: a damaged count (Frames: 100000000) would overflow or
            // take gigabytes. The lines left bound the frames; too few are reported below.
            int line = tokens.NextLine;
            long capacity = Math.Min(frames, Math.Max(0, lines.Length - line));
            var motion = new float[capacity * channels];
            int frame = 0;
            for (; line < lines.Length && frame < frames; line++)
            {
                string text = lines[line].Trim();
                if (text.Length == 0) continue;
                var cells = text.Split((char[])null, StringSplitOptions.RemoveEmptyEntries);
                if (cells.Length != channels)
                    throw Error(source, line, $"frame {frame} has {cells.Length} values, the hierarchy has {channels} channels");
                for (int c = 0; c < channels; c++)
                {
                    if (!float.TryParse(cells[c], NumberStyles.Float, CultureInfo.InvariantCulture, out float v) || !float.IsFinite(v))
                        throw Error(source, line, $"frame {frame} value {c + 1} '{cells[c]}' is not a finite number");
                    motion[(long)frame * channels + c] = v;
                }
                frame++;
            }
            if (frame < frames)
                throw Error(source, lines.Length - 1, $"the header says {frames} frames, the file holds {frame}");
            // Lines after the counted frames are what a streaming writer leaves when it stops
            // between writing frames and rewriting the count (the engine's BVH writer, a crash):
            // the counted frames are whole, the rest may end mid-line. Left out and counted, as
            // other BVH readers read the first `Frames:` frames.
            int ignored = 0;
            for (; line < lines.Length; line++)
                if (lines[line].Trim().Length != 0) ignored++;
            return new BvhFile(joints, channels, frames, frameTime, motion) { IgnoredTrailingLines = ignored };
        }

        static void ParseJoint(Tokens tokens, List<BvhJoint> joints, int parent, ref int channelTotal)
        {
            string name = tokens.Next("joint name");
            if (name == "{") throw tokens.Error("a joint needs a name");
            tokens.Expect("{");
            tokens.Expect("OFFSET");
            var offset = tokens.NextVec3("OFFSET");
            var channels = Array.Empty<BvhChannel>();
            if (tokens.PeekIs("CHANNELS"))
            {
                tokens.Next();
                int n = tokens.NextInt("channel count");
                if (n < 0 || n > 6) throw tokens.Error($"{name}: {n} channels (0..6)");
                channels = new BvhChannel[n];
                for (int c = 0; c < n; c++)
                {
                    string channel = tokens.Next("channel name");
                    if (!Enum.TryParse(channel, ignoreCase: true, out channels[c]) || !Enum.IsDefined(typeof(BvhChannel), channels[c]))
                        throw tokens.Error($"{name}: unknown channel '{channel}'");
                }
            }
            int index = joints.Count;
            joints.Add(new BvhJoint(name, parent, offset, channels, channelTotal));
            channelTotal += channels.Length;
            for (;;)
            {
                if (tokens.PeekIs("}")) { tokens.Next(); return; }
                string word = tokens.Next("JOINT, End Site or '}'");
                if (word == "JOINT")
                {
                    ParseJoint(tokens, joints, index, ref channelTotal);
                }
                else if (word == "End")
                {
                    tokens.Expect("Site");
                    tokens.Expect("{");
                    tokens.Expect("OFFSET");
                    joints[index].EndSite = tokens.NextVec3("End Site OFFSET");
                    tokens.Expect("}");
                }
                else throw tokens.Error($"{name}: expected JOINT, End Site or '}}', found '{word}'");
            }
        }

        static MocapException Error(string source, int line, string what) =>
            new MocapException(MocapStatus.Format, $"{source} line {line + 1}: {what}");

        /// <summary>Whitespace-separated tokens of the HIERARCHY part, with their line numbers.</summary>
        sealed class Tokens
        {
            readonly string[] _lines;
            readonly string _source;
            string[] _cells = Array.Empty<string>();
            int _line = -1, _cell;

            public Tokens(string[] lines, string source)
            {
                _lines = lines;
                _source = source;
            }

            /// <summary>The line after the current token's (where MOTION data starts).</summary>
            public int NextLine => _line + 1;

            bool Fill()
            {
                while (_cell >= _cells.Length)
                {
                    if (_line + 1 >= _lines.Length) return false;
                    _line++;
                    _cells = _lines[_line].Split((char[])null, StringSplitOptions.RemoveEmptyEntries);
                    _cell = 0;
                }
                return true;
            }

            public bool PeekIs(string word) => Fill() && _cells[_cell] == word;

            public string Next(string what = "a token")
            {
                if (!Fill()) throw new MocapException(MocapStatus.Format, $"{_source}: unexpected end of file, expected {what}");
                return _cells[_cell++];
            }

            public void Expect(string word)
            {
                string found = Next($"'{word}'");
                if (!string.Equals(found, word, StringComparison.OrdinalIgnoreCase))
                    throw Error($"expected '{word}', found '{found}'");
            }

            public int NextInt(string what)
            {
                string s = Next(what);
                if (!int.TryParse(s, NumberStyles.Integer, CultureInfo.InvariantCulture, out int v) || v < 0)
                    throw Error($"{what} '{s}' is not a non-negative integer");
                return v;
            }

            public double NextDouble(string what)
            {
                string s = Next(what);
                if (!double.TryParse(s, NumberStyles.Float, CultureInfo.InvariantCulture, out double v) || double.IsNaN(v))
                    throw Error($"{what} '{s}' is not a number");
                return v;
            }

            public Vec3 NextVec3(string what)
            {
                float x = (float)NextDouble(what), y = (float)NextDouble(what), z = (float)NextDouble(what);
                var v = new Vec3(x, y, z);
                if (!v.IsFinite) throw Error($"{what} {v} is not finite");
                return v;
            }

            public MocapException Error(string what) => BvhFile.Error(_source, Math.Max(_line, 0), what);
        }
    }
}
