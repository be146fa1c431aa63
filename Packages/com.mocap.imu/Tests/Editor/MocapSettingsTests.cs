// EditMode: a character's sensor list as Unity serializes it. Settings saved before sensor sets
// (six node ids, one per segment of the six) load as the equivalent sensor list; a new source
// holds the engine's default six; the list reaches the session config in order.

using NUnit.Framework;
using UnityEditor;

namespace Mocap.Imu.Tests
{
    public sealed class MocapSettingsTests
    {
        [Test]
        public void ACharacterSavedWithSixNodeIdsLoadsAsASensorList()
        {
            var source = new MocapCharacterSource();
            EditorJsonUtility.FromJsonOverwrite("{\"name\":\"Old\",\"nodeIds\":[10,11,12,-1,14,15]}", source);
            var expected = new[]
            {
                (MocapSegment.Pelvis, 10), (MocapSegment.LeftWrist, 11), (MocapSegment.RightWrist, 12),
                (MocapSegment.RightShin, 14), (MocapSegment.Head, 15),
            };
            Assert.AreEqual(expected.Length, source.sensors.Count, "the segment without a sensor (-1) is left out");
            for (int i = 0; i < expected.Length; i++)
            {
                Assert.AreEqual(expected[i].Item1, source.sensors[i].segment, $"sensor {i}");
                Assert.AreEqual(expected[i].Item2, source.sensors[i].nodeId, $"sensor {i}");
                Assert.IsFalse(source.sensors[i].optional);
            }
            // Saved again, the old field is gone and the list stays as it is.
            var again = new MocapCharacterSource();
            EditorJsonUtility.FromJsonOverwrite(EditorJsonUtility.ToJson(source), again);
            Assert.AreEqual(expected.Length, again.sensors.Count);
            Assert.AreEqual(15, again.sensors[4].nodeId);
        }

        [Test]
        public void ANewCharacterHoldsTheDefaultSixAndPassesItsListOn()
        {
            var source = new MocapCharacterSource { source = MocapSourceKind.Serial, port = "COM3" };
            Assert.AreEqual(6, source.sensors.Count);
            var config = source.ToSessionConfig(0f, null);
            CollectionAssert.AreEqual(SegmentTable.DefaultSet(), config.Sensors, "the default six are the engine's default set");

            source.sensors.Insert(1, new MocapSensorSlot(MocapSegment.Chest, 6, optional: true));
            config = source.ToSessionConfig(0f, null);
            Assert.AreEqual(7, config.Sensors.Count);
            Assert.AreEqual(new SessionSensor(MocapSegment.Chest, 6, true), config.Sensors[1]);

            source.sensors.Clear();
            var e = Assert.Throws<System.ArgumentException>(() => source.ToSessionConfig(0f, null));
            StringAssert.Contains("no sensors", e.Message);
        }
    }
}
