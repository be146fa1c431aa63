using System;

namespace Mocap.Imu
{
    /// <summary>Sensor sets that settings start from or were saved with, without asking the engine.</summary>
    public static class SensorSets
    {
        // The six of the engine's default set (a test keeps them equal to SegmentTable.DefaultSet),
        // in the order settings written before sensor sets stored their node ids.
        static readonly MocapSegment[] Six =
        {
            MocapSegment.Pelvis, MocapSegment.LeftWrist, MocapSegment.RightWrist,
            MocapSegment.LeftShin, MocapSegment.RightShin, MocapSegment.Head,
        };

        /// <summary>
        /// The six sensors pelvis, both wrists, both shins and head on nodes 0..5: the engine's
        /// default set, for serialized settings whose initial values cannot call the engine.
        /// </summary>
        public static SessionSensor[] DefaultSix()
        {
            var set = new SessionSensor[Six.Length];
            for (int i = 0; i < Six.Length; i++) set[i] = new SessionSensor(Six[i], i);
            return set;
        }

        /// <summary>
        /// The sensor set of settings saved before sensor sets: one node id per segment of the six
        /// (pelvis, left wrist, right wrist, left shin, right shin, head), -1 for a segment without
        /// a sensor, which is left out.
        /// </summary>
        /// <exception cref="ArgumentException">Not six entries.</exception>
        public static SessionSensor[] FromNodeIdsOfTheSix(int[] nodeIds)
        {
            if (nodeIds == null) throw new ArgumentNullException(nameof(nodeIds));
            if (nodeIds.Length != Six.Length)
                throw new ArgumentException(
                    $"{nodeIds.Length} node ids; settings saved before sensor sets hold one for each of the six segments",
                    nameof(nodeIds));
            int kept = 0;
            foreach (int id in nodeIds) if (id >= 0) kept++;
            var set = new SessionSensor[kept];
            int k = 0;
            for (int i = 0; i < Six.Length; i++)
                if (nodeIds[i] >= 0) set[k++] = new SessionSensor(Six[i], nodeIds[i]);
            return set;
        }
    }
}
