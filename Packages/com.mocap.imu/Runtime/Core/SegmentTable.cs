using System;
using System.Collections.Generic;
using System.Text;

namespace Mocap.Imu
{
    /// <summary>
    /// The engine's segment table (Native~/src/imu/segments.def, read through mocap_segment_*):
    /// each body segment's name, the SMPL joint whose bone its sensor follows, and its node id in
    /// the default sensor set. The table is read once, on first use, so it is never copied here.
    /// </summary>
    public static class SegmentTable
    {
        sealed class Rows
        {
            public string[] Names;
            public int[] Joints;
            public int[] DefaultNodes;
        }

        static Rows _rows;

        /// <summary>Segments in the engine's table (valid values are 0 .. Count-1).</summary>
        public static int Count => Table.Names.Length;

        /// <summary>Whether the loaded engine knows <paramref name="segment"/>.</summary>
        public static bool Contains(MocapSegment segment) => (uint)segment < (uint)Count;

        /// <summary>The engine's name of a segment, e.g. "left_wrist".</summary>
        public static string Name(MocapSegment segment) => Table.Names[Index(segment)];

        /// <summary>The SMPL-24 joint (contract order) whose bone the segment's sensor follows.</summary>
        public static int SmplJoint(MocapSegment segment) => Table.Joints[Index(segment)];

        /// <summary>The segment's node id in the default sensor set, or -1 when that set leaves it out.</summary>
        public static int DefaultNode(MocapSegment segment) => Table.DefaultNodes[Index(segment)];

        /// <summary>The segment the engine calls <paramref name="name"/> (exact, lower case).</summary>
        public static unsafe bool TryFind(string name, out MocapSegment segment)
        {
            segment = default;
            if (string.IsNullOrEmpty(name) || name.IndexOf('\0') >= 0) return false;
            MocapEngine.EnsureCompatible();
            var utf8 = NativeText.ToNullTerminated(name, nameof(name));
            int found;
            fixed (byte* p = utf8) found = NativeMethods.mocap_segment_find(p);
            if (found < 0) return false;
            segment = (MocapSegment)found;
            return true;
        }

        /// <summary>The engine's default sensor set, in segment order: each segment that has a default node.</summary>
        public static SessionSensor[] DefaultSet()
        {
            var rows = Table;
            var set = new List<SessionSensor>();
            for (int s = 0; s < rows.DefaultNodes.Length; s++)
                if (rows.DefaultNodes[s] >= 0) set.Add(new SessionSensor((MocapSegment)s, rows.DefaultNodes[s]));
            return set.ToArray();
        }

        /// <summary>
        /// The lower-case name of a segment derived from its enum member ("LeftWrist" to
        /// "left_wrist"), without the engine: recordings use it so they can be read anywhere. A
        /// test keeps it equal to <see cref="Name"/> for every member.
        /// </summary>
        public static string SnakeName(MocapSegment segment)
        {
            string pascal = segment.ToString();
            var text = new StringBuilder(pascal.Length + 4);
            for (int i = 0; i < pascal.Length; i++)
            {
                char c = pascal[i];
                if (char.IsUpper(c) && i > 0) text.Append('_');
                text.Append(char.ToLowerInvariant(c));
            }
            return text.ToString();
        }

        /// <summary>The enum member whose <see cref="SnakeName"/> is <paramref name="name"/>; no engine needed.</summary>
        public static bool TryParseSnakeName(string name, out MocapSegment segment)
        {
            foreach (MocapSegment candidate in Enum.GetValues(typeof(MocapSegment)))
                if (string.Equals(SnakeName(candidate), name, StringComparison.Ordinal))
                {
                    segment = candidate;
                    return true;
                }
            segment = default;
            return false;
        }

        /// <summary>The name people read ("left wrist"); no engine needed.</summary>
        public static string DisplayName(MocapSegment segment) =>
            Enum.IsDefined(typeof(MocapSegment), segment)
                ? SnakeName(segment).Replace('_', ' ')
                : "segment " + ((int)segment).ToString(System.Globalization.CultureInfo.InvariantCulture);

        static int Index(MocapSegment segment)
        {
            var rows = Table;
            if ((uint)segment >= (uint)rows.Names.Length)
                throw new ArgumentOutOfRangeException(nameof(segment), (int)segment,
                    $"the engine's segment table has {rows.Names.Length} segments");
            return (int)segment;
        }

        static Rows Table
        {
            get
            {
                var rows = System.Threading.Volatile.Read(ref _rows);
                if (rows != null) return rows;
                MocapEngine.EnsureCompatible();
                int count = NativeMethods.mocap_segment_count();
                if (count <= 0)
                    throw new MocapException(MocapStatus.Format, $"the engine reports {count} body segments");
                rows = new Rows { Names = new string[count], Joints = new int[count], DefaultNodes = new int[count] };
                for (int s = 0; s < count; s++)
                {
                    rows.Names[s] = NativeText.FromPointer(NativeMethods.mocap_segment_name(s));
                    rows.Joints[s] = NativeMethods.mocap_segment_joint(s);
                    rows.DefaultNodes[s] = NativeMethods.mocap_segment_default_node(s);
                }
                // Several threads may build it at once: each builds the same rows.
                System.Threading.Volatile.Write(ref _rows, rows);
                return rows;
            }
        }
    }
}
