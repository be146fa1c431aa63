// The VMC sender binding end to end: poses of a replayed capture go through VmcSender to a
// UdpClient bound to 127.0.0.1, which parses each datagram as an OSC bundle and checks the
// messages against the pose (bone names, Unity coordinates, local rotations, root split).

using System;
using System.Collections.Generic;
using System.Net;
using System.Net.Sockets;
using System.Text;
using Mocap.Imu.Maths;
using Mocap.Imu.Retarget;
using Mocap.Imu.Skeleton;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    /// <summary>A minimal OSC reader: a bundle of messages with string, int and float arguments.</summary>
    internal static class Osc
    {
        public sealed class Message
        {
            public string Address;
            public readonly List<object> Args = new List<object>();
        }

        public static List<Message> ParseBundle(byte[] data)
        {
            int o = 0;
            Assert.AreEqual("#bundle", ReadString(data, ref o), "not an OSC bundle");
            o += 8; // time tag
            var messages = new List<Message>();
            while (o < data.Length)
            {
                int size = ReadInt(data, ref o);
                Assert.That(size > 0 && o + size <= data.Length, $"element size {size} at {o} overruns the {data.Length}-byte bundle");
                messages.Add(ParseMessage(data, o, size));
                o += size;
            }
            return messages;
        }

        static Message ParseMessage(byte[] data, int start, int size)
        {
            int o = start;
            var m = new Message { Address = ReadString(data, ref o) };
            string tags = ReadString(data, ref o);
            Assert.That(tags.StartsWith(","), $"{m.Address}: no type tag string");
            foreach (char t in tags.Substring(1))
            {
                switch (t)
                {
                    case 's': m.Args.Add(ReadString(data, ref o)); break;
                    case 'i': m.Args.Add(ReadInt(data, ref o)); break;
                    case 'f':
                        int bits = ReadInt(data, ref o);
                        m.Args.Add(BitConverter.Int32BitsToSingle(bits));
                        break;
                    default: Assert.Fail($"{m.Address}: unexpected OSC type '{t}'"); break;
                }
            }
            Assert.AreEqual(start + size, o, $"{m.Address}: arguments do not fill the element");
            return m;
        }

        static string ReadString(byte[] data, ref int o)
        {
            int end = Array.IndexOf(data, (byte)0, o);
            Assert.That(end >= 0, "unterminated OSC string");
            string s = Encoding.UTF8.GetString(data, o, end - o);
            o = (end + 4) & ~3; // NUL included, padded to 4
            return s;
        }

        static int ReadInt(byte[] data, ref int o)
        {
            int v = (data[o] << 24) | (data[o + 1] << 16) | (data[o + 2] << 8) | data[o + 3];
            o += 4;
            return v;
        }
    }

    [TestFixture]
    public sealed class VmcSenderTests
    {
        MocapModel _model;
        List<MocapPose> _poses;
        UdpClient _receiver;
        string _destination;

        [OneTimeSetUp]
        public void ReplayPoses()
        {
            TestPaths.RequireEngine();
            var capture = TestPaths.Synth("walk", seconds: 6, seed: 3);
            _model = MocapModel.Open(TestPaths.ModelPath);
            _poses = SolverReplay.SolveOneCharacter(capture, _model);
            Assert.Greater(_poses.Count, 60, "the replay produced too few poses to stream");
        }

        [OneTimeTearDown]
        public void CloseModel() => _model?.Dispose();

        [SetUp]
        public void OpenReceiver()
        {
            _receiver = new UdpClient(new IPEndPoint(IPAddress.Loopback, 0));
            _receiver.Client.ReceiveTimeout = 2000;
            _receiver.Client.ReceiveBufferSize = 1 << 20; // the OS may cap it: bursts are kept small
            _destination = "127.0.0.1:" + ((IPEndPoint)_receiver.Client.LocalEndPoint).Port;
        }

        [TearDown]
        public void CloseReceiver() => _receiver?.Dispose();

        byte[] Receive()
        {
            var from = new IPEndPoint(IPAddress.Any, 0);
            try
            {
                return _receiver.Receive(ref from);
            }
            catch (SocketException e)
            {
                Assert.Fail($"no datagram from the VMC sender within 2 s: {e.Message}");
                return null;
            }
        }

        static float[] Floats(Osc.Message m, int first)
        {
            var f = new float[m.Args.Count - first];
            for (int i = 0; i < f.Length; i++) f[i] = (float)m.Args[first + i];
            return f;
        }

        [Test]
        public void EveryPoseArrivesAsOneBundleWithTheHumanoidBones()
        {
            var options = new VmcOptions { MaxRateHz = 0 }; // every pose
            using var sender = VmcSender.Open(_model, _destination, options);
            Assert.AreEqual(_destination, sender.Destination);
            var restOffsets = _model.Info.RestOffsets;
            int checkedPoses = 0;
            for (int i = 0; i < _poses.Count; i += 7)
            {
                var pose = _poses[i];
                Assert.AreEqual(VmcSendResult.Sent, sender.Send(in pose), $"pose {i}");
                var messages = Osc.ParseBundle(Receive());

                var bones = new Dictionary<string, float[]>();
                float[] root = null;
                bool ok = false, time = false;
                foreach (var m in messages)
                {
                    switch (m.Address)
                    {
                        case "/VMC/Ext/Bone/Pos":
                            Assert.AreEqual(8, m.Args.Count, "Bone/Pos takes a name and 7 floats");
                            bones.Add((string)m.Args[0], Floats(m, 1));
                            break;
                        case "/VMC/Ext/Root/Pos":
                            Assert.AreEqual("root", m.Args[0]);
                            root = Floats(m, 1);
                            break;
                        case "/VMC/Ext/OK":
                            Assert.AreEqual(1, m.Args[0]);
                            ok = true;
                            break;
                        case "/VMC/Ext/T":
                            Assert.AreEqual((float)pose.TimeSeconds, (float)m.Args[0], 1e-3f, "/VMC/Ext/T");
                            time = true;
                            break;
                    }
                }
                Assert.IsTrue(ok, "no /VMC/Ext/OK");
                Assert.IsTrue(time, "no /VMC/Ext/T");
                Assert.IsNotNull(root, "no /VMC/Ext/Root/Pos");

                // Every bone the SMPL pose drives, by its HumanBodyBones name, nothing else.
                CollectionAssert.AreEquivalent(MappedBoneNames(), bones.Keys, $"pose {i}: bone names");

                // Root = pelvis world position minus its rest offset, identity rotation.
                Vec3 rootExpected = CoordinateConversion.ModelToUnity(pose.RootPosition - restOffsets[0]);
                AssertVec(rootExpected, root, 1e-4f, $"pose {i}: Root/Pos position");
                AssertQuat(Quat.Identity, root, $"pose {i}: Root/Pos rotation");

                // Hips: the pelvis rest offset and the global pelvis rotation, in Unity's frame.
                AssertVec(CoordinateConversion.ModelToUnity(restOffsets[0]), bones["Hips"], 1e-4f, $"pose {i}: Hips position");
                AssertQuat(CoordinateConversion.ModelToUnity(pose.GetJointRotation(SmplJoint.Pelvis)), bones["Hips"], $"pose {i}: Hips rotation");

                // Other bones: rest offset from the parent and the joint's local rotation.
                foreach (var joint in new[] { SmplJoint.LeftElbow, SmplJoint.RightKnee, SmplJoint.Head, SmplJoint.Spine3 })
                {
                    string name = HumanoidBoneMap.Name(HumanoidBoneMap.ToHumanBone(joint));
                    AssertVec(CoordinateConversion.ModelToUnity(restOffsets[(int)joint]), bones[name], 1e-4f, $"pose {i}: {name} offset");
                    AssertQuat(CoordinateConversion.ModelToUnity(pose.GetJointRotation(joint)), bones[name], $"pose {i}: {name} rotation");
                }
                checkedPoses++;
            }

            var stats = sender.GetStats();
            Assert.AreEqual((ulong)checkedPoses, stats.BundlesSent);
            Assert.AreEqual((ulong)checkedPoses, stats.Poses);
            Assert.AreEqual(0UL, stats.SendFailures);
            Assert.AreEqual(22u, stats.BonesPerBundle);
            Assert.Greater(stats.LastBundleSize, 22u * 48u, "a bundle of 22 Bone/Pos messages is larger");
        }

        [Test]
        public void TheRateCapSkipsPosesAndSaysSo()
        {
            using var sender = VmcSender.Open(_model, _destination, new VmcOptions { MaxRateHz = 10 });
            int sent = 0, skipped = 0;
            double first = _poses[0].TimeSeconds, last = first;
            foreach (var pose in _poses)
            {
                var result = sender.Send(in pose);
                if (result == VmcSendResult.Sent)
                {
                    sent++;
                    Assert.AreEqual(22, CountBones(Osc.ParseBundle(Receive())));
                }
                else if (result == VmcSendResult.RateLimited) skipped++;
                else Assert.Fail($"unexpected {result}");
                last = pose.TimeSeconds;
            }
            double seconds = last - first;
            TestContext.WriteLine($"{_poses.Count} poses over {seconds:F2} s: {sent} sent, {skipped} skipped");
            Assert.LessOrEqual(sent, (int)Math.Ceiling(seconds * 10) + 1, "more bundles than 10 per second of pose time");
            Assert.GreaterOrEqual(sent, (int)Math.Floor(seconds * 10) - 1, "the cap dropped more than it should");
            var stats = sender.GetStats();
            Assert.AreEqual((ulong)skipped, stats.SkippedRate);
            Assert.AreEqual((ulong)sent, stats.BundlesSent);
        }

        [Test]
        public void ARemoteDestinationIsRefusedUnlessAllowed()
        {
            // 192.0.2.0/24 is TEST-NET-1: never routed, never loopback.
            var e = Assert.Throws<MocapException>(() => VmcSender.Open(_model, "192.0.2.1:39539"));
            Assert.AreEqual(MocapStatus.Permission, e.Status, e.Message);
            Assert.That(e.Message, Does.Contain("192.0.2.1"), "the message names the destination");
            Assert.Throws<MocapException>(() => VmcSender.Open(_model, "not a host:99999"));
        }

        [Test]
        public void SendingAllocatesNothingAndOutlivesTheModel()
        {
            using var model = MocapModel.Open(TestPaths.ModelPath);
            using var sender = VmcSender.Open(model, _destination, new VmcOptions { MaxRateHz = 0 });
            model.Dispose();
            var poses = _poses.ToArray();
            Assert.AreEqual(VmcSendResult.Sent, sender.Send(in poses[0])); // warm-up (JIT)
            sender.GetStats();
            Receive();
            // A burst the default socket buffer of any OS holds (about 30 KB), read after the
            // measurement because receiving allocates.
            const int Sends = 16;
            long before = GC.GetAllocatedBytesForCurrentThread();
            int sent = 0;
            for (int i = 0; i < Sends; i++)
                if (sender.Send(in poses[i % poses.Length]) == VmcSendResult.Sent) sent++;
            var stats = sender.GetStats();
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Assert.AreEqual(0, allocated, "Send/GetStats allocated");
            Assert.AreEqual(Sends, sent);
            Assert.AreEqual((ulong)(Sends + 1), stats.BundlesSent);
            for (int i = 0; i < Sends; i++) Assert.AreEqual(22, CountBones(Osc.ParseBundle(Receive())));
        }

        [Test]
        public void ADisposedSenderThrows()
        {
            var sender = VmcSender.Open(_model, _destination);
            sender.Dispose();
            sender.Dispose();
            var pose = _poses[0];
            Assert.Throws<ObjectDisposedException>(() => sender.Send(in pose));
        }

        static int CountBones(List<Osc.Message> messages)
        {
            int n = 0;
            foreach (var m in messages) if (m.Address == "/VMC/Ext/Bone/Pos") n++;
            return n;
        }

        static List<string> MappedBoneNames()
        {
            var names = new List<string>();
            foreach (var b in HumanoidBoneMap.MappedBones) names.Add(HumanoidBoneMap.Name(b));
            Assert.AreEqual(22, names.Count);
            return names;
        }

        static void AssertVec(Vec3 expected, float[] f, float tolerance, string where)
        {
            var actual = new Vec3(f[0], f[1], f[2]);
            Assert.IsTrue(expected.ApproximatelyEquals(actual, tolerance), $"{where}: expected {expected}, got {actual}");
        }

        static void AssertQuat(Quat expected, float[] f, string where)
        {
            // VMC order: qx qy qz qw after the position. q and -q are the same rotation.
            var actual = new Quat(f[3], f[4], f[5], f[6]);
            float angle = Quat.Angle(expected, actual);
            Assert.Less(angle, 1e-3f, $"{where}: expected {expected}, got {actual} ({angle} rad apart)");
        }
    }
}
