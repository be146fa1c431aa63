// C and C# cannot drift apart silently: every struct the engine reports in mocap_struct_layout
// must have a C# mirror of the same size whose fields sit at the same offsets with the same
// sizes, and every mirrored C# field must be in the engine's table.

using System;
using System.Collections.Generic;
using System.Linq;
using System.Reflection;
using System.Runtime.InteropServices;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    [TestFixture]
    public sealed unsafe class NativeLayoutTests
    {
        struct Row
        {
            public string Struct, Field;
            public int Offset, Size;
        }

        static readonly string[] ExpectedStructs =
        {
            "mocap_sensor_frame", "mocap_frame", "mocap_session_config", "mocap_session_stats",
            "mocap_sensor_quality", "mocap_calibration_report", "mocap_calibration", "mocap_solver_stats",
        };

        List<Row> _rows;
        Dictionary<string, Type> _mirrors;

        [OneTimeSetUp]
        public void ReadTable()
        {
            TestPaths.RequireEngine();
            uint count;
            NativeFieldLayout* table = NativeMethods.mocap_struct_layout(&count);
            Assert.IsTrue(table != null, "mocap_struct_layout returned NULL");
            _rows = new List<Row>();
            for (int i = 0; i < count; i++)
                _rows.Add(new Row
                {
                    Struct = NativeText.FromPointer(table[i].StructName),
                    Field = NativeText.FromPointer(table[i].FieldName),
                    Offset = (int)table[i].Offset,
                    Size = (int)table[i].Size,
                });
            _mirrors = typeof(MocapSession).Assembly.GetTypes()
                .Where(t => t.GetCustomAttribute<NativeNameAttribute>() != null)
                .ToDictionary(t => t.GetCustomAttribute<NativeNameAttribute>().Name);
        }

        [Test]
        public void EveryEngineStructHasAMirror()
        {
            var structs = _rows.Where(r => r.Field.Length == 0).Select(r => r.Struct).ToList();
            CollectionAssert.IsSubsetOf(ExpectedStructs, structs, "the engine's table lost a struct");
            foreach (var name in structs)
                Assert.IsTrue(_mirrors.ContainsKey(name), $"no C# mirror of {name}");
            CollectionAssert.AreEquivalent(structs, _mirrors.Keys, "a C# mirror of a struct the engine does not report");
        }

        [Test]
        public void StructSizesMatch()
        {
            foreach (var row in _rows.Where(r => r.Field.Length == 0))
            {
                var type = _mirrors[row.Struct];
                Assert.AreEqual(row.Size, Marshal.SizeOf(type), $"sizeof({row.Struct}) vs Marshal.SizeOf({type.Name})");
                Assert.AreEqual(row.Size, ManagedStride(type),
                    $"sizeof({row.Struct}) vs the managed array stride of {type.Name} (what drain writes into)");
            }
        }

        [Test]
        public void FieldOffsetsAndSizesMatch()
        {
            foreach (var row in _rows.Where(r => r.Field.Length > 0))
            {
                string where = $"{row.Struct}.{row.Field}";
                Assert.IsTrue(_mirrors.TryGetValue(row.Struct, out var type), $"no mirror for {where}");
                var field = MirroredFields(type).FirstOrDefault(f => f.GetCustomAttribute<NativeNameAttribute>().Name == row.Field);
                Assert.IsNotNull(field, $"{type.Name} has no field mirroring {where}");
                int offset = (int)Marshal.OffsetOf(type, field.Name);
                Assert.AreEqual(row.Offset, offset, $"offset of {where} vs {type.Name}.{field.Name}");
                Assert.AreEqual(row.Size, SizeOfField(field.FieldType), $"size of {where} vs {type.Name}.{field.Name}");
            }
        }

        [Test]
        public void StructArraysInFixedBuffersHaveTheEnginesElementSize()
        {
            // MocapFrame and CalibrationReport keep their [16] struct arrays in fixed buffers read
            // through pointer casts: the element stride must be the engine's sizeof.
            Assert.AreEqual(EngineSize("mocap_sensor_frame"), sizeof(MocapSensorFrame));
            Assert.AreEqual(EngineSize("mocap_sensor_frame"), MocapFrame.SensorFrameWords * sizeof(uint));
            Assert.AreEqual(EngineSize("mocap_sensor_frame") * MocapSession.MaxSensors, FieldSize("mocap_frame", "sensors"));
            Assert.AreEqual(EngineSize("mocap_sensor_quality") * MocapSession.MaxSensors, FieldSize("mocap_calibration_report", "sensors"));
            Assert.AreEqual(EngineSize("mocap_sensor_quality"), sizeof(SensorQuality));
        }

        int EngineSize(string structName) => _rows.Single(r => r.Struct == structName && r.Field.Length == 0).Size;
        int FieldSize(string structName, string field) => _rows.Single(r => r.Struct == structName && r.Field == field).Size;

        [Test]
        public void FrameSensorsAreReadAndWrittenByIndexAndFoundBySegment()
        {
            var frame = new MocapFrame { SensorCount = 7 };
            for (int i = 0; i < 7; i++)
                frame.SetSensor(i, new MocapSensorFrame { Segment = (MocapSegment)(6 - i), NodeId = (uint)(10 + i), AgeSeconds = i });
            Assert.AreEqual(7, frame.SensorCount);
            Assert.AreEqual(0, frame.IndexOf(MocapSegment.Chest));
            Assert.AreEqual(6, frame.IndexOf(MocapSegment.Pelvis));
            Assert.IsTrue(frame.TryGetSensor(MocapSegment.LeftShin, out var shin));
            Assert.AreEqual(13u, shin.NodeId);
            Assert.AreEqual(3f, frame.GetSensor(3).AgeSeconds);
            // Byte-exact in the engine's layout: sensor i sits at sensors + i * sizeof.
            byte* bytes = (byte*)&frame;
            int sensors = _rows.Single(r => r.Struct == "mocap_frame" && r.Field == "sensors").Offset;
            var fifth = (MocapSensorFrame*)(bytes + sensors + 5 * sizeof(MocapSensorFrame));
            Assert.AreEqual(MocapSegment.LeftWrist, fifth->Segment);
            Assert.AreEqual(15u, fifth->NodeId);

            frame.SensorCount = 2;
            Assert.AreEqual(-1, frame.IndexOf(MocapSegment.Pelvis), "only the first SensorCount sensors count");
            Assert.AreEqual(1, frame.IndexOf(MocapSegment.Head));
            Assert.IsFalse(frame.TryGetSensor(MocapSegment.Pelvis, out _));
            var copy = frame;
            Assert.Throws<ArgumentOutOfRangeException>(() => copy.GetSensor(2));
            Assert.Throws<ArgumentOutOfRangeException>(() => copy.SetSensor(-1, default));
            Assert.Throws<ArgumentOutOfRangeException>(() => copy.SensorCount = MocapSession.MaxSensors + 1);
        }

        [Test]
        public void EveryMirroredFieldIsInTheEngineTable()
        {
            foreach (var pair in _mirrors)
                foreach (var field in MirroredFields(pair.Value))
                {
                    string name = field.GetCustomAttribute<NativeNameAttribute>().Name;
                    Assert.IsTrue(_rows.Any(r => r.Struct == pair.Key && r.Field == name),
                        $"{pair.Value.Name}.{field.Name} claims to mirror {pair.Key}.{name}, which the engine does not report");
                }
        }

        [Test]
        public void MirrorsAreBlittable()
        {
            foreach (var type in _mirrors.Values)
            {
                // Pinning throws for any type with a non-blittable field (bool, char, string, array).
                var handle = GCHandle.Alloc(Activator.CreateInstance(type), GCHandleType.Pinned);
                handle.Free();
            }
        }

        [Test]
        public void StatusNamesMatchTheEngine()
        {
            foreach (MocapStatus status in Enum.GetValues(typeof(MocapStatus)))
            {
                string expected = status == MocapStatus.Ok ? "MOCAP_OK" : "MOCAP_ERR_" + UpperSnake(status.ToString());
                Assert.AreEqual(expected, MocapEngine.StatusName(status), $"MocapStatus.{status} = {(int)status}");
            }
        }

        [Test]
        public void SegmentNamesMatchTheEngine()
        {
            foreach (MocapSegment segment in Enum.GetValues(typeof(MocapSegment)))
                Assert.AreEqual(UpperSnake(segment.ToString()).ToLowerInvariant(), MocapEngine.SegmentName(segment));
            Assert.AreEqual(SegmentTable.Count, Enum.GetValues(typeof(MocapSegment)).Length);
        }

        [Test]
        public void DefaultConfigEqualsTheEngineDefaultsByteForByte()
        {
            NativeSessionConfig engine;
            Assert.AreEqual(MocapStatus.Ok, NativeMethods.mocap_config_defaults(&engine));
            new SessionConfig().ToNative(out var mine);
            var a = new ReadOnlySpan<byte>(&engine, sizeof(NativeSessionConfig));
            var b = new ReadOnlySpan<byte>(&mine, sizeof(NativeSessionConfig));
            for (int i = 0; i < a.Length; i++) Assert.AreEqual(a[i], b[i], $"byte {i} of mocap_session_config");
            Assert.AreEqual(sizeof(NativeSessionConfig), (int)mine.StructSize);
        }

        [Test]
        public void ConfigStringsAreUtf8AndBounded()
        {
            var config = SessionConfig.Replay("caf\u00e9/\u00fcber.cap");
            config.ToNative(out var native);
            Assert.AreEqual("caf\u00e9/\u00fcber.cap", NativeText.FromBuffer(native.Path, NativeMethods.PathMax));
            Assert.AreEqual(0x63, native.Path[0]);
            Assert.AreEqual(0xC3, native.Path[3], "UTF-8, not Latin-1 or UTF-16");
            config.Path = new string('x', 259);
            config.ToNative(out _);
            config.Path = new string('x', 260);
            var e = Assert.Throws<ArgumentException>(() => config.ToNative(out _));
            StringAssert.Contains("Path", e.Message);
        }

        static IEnumerable<FieldInfo> MirroredFields(Type type) =>
            type.GetFields(BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic)
                .Where(f => f.GetCustomAttribute<NativeNameAttribute>() != null);

        static int SizeOfField(Type fieldType) =>
            Marshal.SizeOf(fieldType.IsEnum ? Enum.GetUnderlyingType(fieldType) : fieldType);

        // Distance between two elements of a pinned managed array: the layout the engine writes
        // into when C# passes an array, which Marshal.SizeOf alone does not prove.
        static int ManagedStride(Type type)
        {
            var array = Array.CreateInstance(type, 2);
            var handle = GCHandle.Alloc(array, GCHandleType.Pinned);
            try
            {
                return (int)((long)Marshal.UnsafeAddrOfPinnedArrayElement(array, 1) -
                             (long)Marshal.UnsafeAddrOfPinnedArrayElement(array, 0));
            }
            finally
            {
                handle.Free();
            }
        }

        static string UpperSnake(string pascal)
        {
            var text = new System.Text.StringBuilder();
            for (int i = 0; i < pascal.Length; i++)
            {
                if (i > 0 && char.IsUpper(pascal[i]) && char.IsLower(pascal[i - 1])) text.Append('_');
                text.Append(char.ToUpperInvariant(pascal[i]));
            }
            return text.ToString();
        }
    }
}
