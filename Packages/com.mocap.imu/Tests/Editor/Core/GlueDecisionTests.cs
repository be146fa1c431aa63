// The decisions the Unity components take, tested here because the components only apply them:
// the physics character's link lifecycle, the overlay's magnification and its world-space text.

using System;
using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    public sealed class PhysicsLinkTrackerTests
    {
        [Test]
        public void LinksAreBuiltOnceForARigAndKept()
        {
            var tracker = new PhysicsLinkTracker();
            var rig = new object();
            Assert.AreEqual(PhysicsLinkAction.Keep, tracker.Check(null, false), "no rig, no links: nothing to do");
            Assert.AreEqual(PhysicsLinkAction.Build, tracker.Check(rig, false));
            tracker.Built(rig);
            Assert.AreSame(rig, tracker.BuiltFor);
            Assert.AreEqual(PhysicsLinkAction.Keep, tracker.Check(rig, false));
        }

        [Test]
        public void ARebuiltRigRebuildsTheLinks()
        {
            var tracker = new PhysicsLinkTracker();
            var first = new object();
            tracker.Built(first);
            tracker.IgnoresApplied();
            var second = new object();
            Assert.AreEqual(PhysicsLinkAction.Rebuild, tracker.Check(second, false));
            tracker.Built(second);
            Assert.AreEqual(PhysicsLinkAction.Keep, tracker.Check(second, false));
            Assert.IsTrue(tracker.NeedsIgnores, "new links need their ignores");
        }

        [Test]
        public void NoRigOrADestroyedBoneDropsTheLinks()
        {
            var tracker = new PhysicsLinkTracker();
            var rig = new object();
            tracker.Built(rig);
            Assert.AreEqual(PhysicsLinkAction.Clear, tracker.Check(rig, anyBoneDestroyed: true));
            Assert.AreEqual(PhysicsLinkAction.Clear, tracker.Check(null, false));
            tracker.Cleared();
            Assert.IsNull(tracker.BuiltFor);
            Assert.IsFalse(tracker.NeedsIgnores);
            Assert.AreEqual(PhysicsLinkAction.Keep, tracker.Check(rig, anyBoneDestroyed: true), "nothing left to drop");
        }

        [Test]
        public void IgnoresAreAppliedAgainAfterEveryDeactivation()
        {
            var tracker = new PhysicsLinkTracker();
            Assert.IsFalse(tracker.NeedsIgnores, "no links: nothing to ignore");
            tracker.Built(new object());
            Assert.IsTrue(tracker.NeedsIgnores);
            tracker.IgnoresApplied();
            Assert.IsFalse(tracker.NeedsIgnores);
            for (int cycle = 0; cycle < 3; cycle++)
            {
                tracker.Deactivated();
                Assert.IsTrue(tracker.NeedsIgnores, $"disable/enable cycle {cycle}");
                tracker.IgnoresApplied();
                Assert.IsFalse(tracker.NeedsIgnores);
            }
        }

        [Test]
        public void IgnoresWithoutLinksStayUnapplied()
        {
            var tracker = new PhysicsLinkTracker();
            tracker.IgnoresApplied();
            tracker.Built(new object());
            Assert.IsTrue(tracker.NeedsIgnores, "marking before a build does not count for the new links");
        }
    }

    public sealed class OverlayScaleTests
    {
        [TestCase(96f, 1f)]
        [TestCase(144f, 1.5f)]
        [TestCase(192f, 2f)]
        [TestCase(288f, 3f)]
        [TestCase(72f, 1f, TestName = "A low-density screen keeps the designed size")]
        [TestCase(0f, 1f, TestName = "Unknown density (Unity reports 0): no scaling")]
        [TestCase(-5f, 1f)]
        [TestCase(float.NaN, 1f)]
        [TestCase(float.PositiveInfinity, 1f)]
        [TestCase(1000f, OverlayScale.MaxScale)]
        public void TheScaleFollowsTheDensity(float dpi, float expected)
        {
            Assert.AreEqual(expected, OverlayScale.For(dpi, 10000f, 10000f, 470f, 340f), 1e-6f);
        }

        [Test]
        public void ThePanelStaysOnScreen()
        {
            // 192 dpi would double a 470 x 340 panel; an 800 x 600 window only fits 1.7x of its width.
            Assert.AreEqual(800f / 470f, OverlayScale.For(192f, 800f, 600f, 470f, 340f), 1e-5f);
            Assert.AreEqual(500f / 340f, OverlayScale.For(192f, 2000f, 500f, 470f, 340f), 1e-5f);
            // Smaller than the panel even unscaled: the designed size, never shrunk below it.
            Assert.AreEqual(1f, OverlayScale.For(192f, 300f, 200f, 470f, 340f));
            // No screen size known (0): density only.
            Assert.AreEqual(2f, OverlayScale.For(192f, 0f, 0f, 470f, 340f));
        }
    }

    public sealed class PanelTextTests
    {
        [Test]
        public void LinesAreJoinedWithNewlinesSkippingNulls()
        {
            var panel = new PanelText(4);
            panel.Begin();
            panel.Add("Mocap IMU - Alice");
            panel.Add(null);
            panel.Add("T-pose");
            Assert.AreEqual("Mocap IMU - Alice\nT-pose", panel.Text);
        }

        [Test]
        public void AnUnchangedPanelReturnsTheSameStringAndAllocatesNothing()
        {
            var panel = new PanelText(3);
            string a = "title", b = "instruction", c = "Collecting: 10%";
            var first = Frame(panel, a, b, c);
            Assert.AreSame(first, Frame(panel, a, b, c));
            Frames(panel, a, b, c, 100);  // warm-up: JIT the loop, the panel and the getter
            // The least of three runs: a per-frame allocation shows in every run, while the
            // runtime's own one-off work (tiering a method up mid-run) shows in one at most.
            long allocated = long.MaxValue;
            for (int run = 0; run < 3; run++)
            {
                long before = GC.GetAllocatedBytesForCurrentThread();
                int length = Frames(panel, a, b, c, 1000);
                long bytes = GC.GetAllocatedBytesForCurrentThread() - before;
                Assert.AreEqual(1000 * first.Length, length);
                allocated = Math.Min(allocated, bytes);
            }
            Assert.AreEqual(0, allocated, "an unchanged panel must not allocate per frame");
        }

        static int Frames(PanelText panel, string a, string b, string c, int count)
        {
            int length = 0;
            for (int i = 0; i < count; i++) length += Frame(panel, a, b, c).Length;
            return length;
        }

        static string Frame(PanelText panel, string a, string b, string c)
        {
            panel.Begin();
            panel.Add(a);
            panel.Add(b);
            panel.Add(c);
            return panel.Text;
        }

        [Test]
        public void AChangedOrDroppedLineRebuildsTheText()
        {
            var panel = new PanelText(3);
            panel.Begin(); panel.Add("a"); panel.Add("b"); panel.Add("c");
            Assert.AreEqual("a\nb\nc", panel.Text);
            panel.Begin(); panel.Add("a"); panel.Add("B"); panel.Add("c");
            Assert.AreEqual("a\nB\nc", panel.Text);
            panel.Begin(); panel.Add("a"); panel.Add("B");
            Assert.AreEqual("a\nB", panel.Text);
            panel.Begin(); panel.Add("a"); panel.Add("B"); panel.Add("c");
            Assert.AreEqual("a\nB\nc", panel.Text);
        }

        [Test]
        public void BadCapacityAndOverflowAreClearErrors()
        {
            Assert.Throws<ArgumentOutOfRangeException>(() => new PanelText(0));
            var panel = new PanelText(1);
            panel.Begin();
            panel.Add("one");
            var e = Assert.Throws<InvalidOperationException>(() => panel.Add("two"));
            StringAssert.Contains("holds 1 lines", e.Message);
        }
    }
}
