// A user's project runs these tests without this repository's engine build: such tests are
// ignored there with the reason, and fail here, where the same absence is a broken setup.

using NUnit.Framework;

namespace Mocap.Imu.Tests
{
    public sealed class RepositoryAbsenceTests
    {
        [TestCase(false, false, true, TestName = "No MOCAP_MOCAPCTL, no repository: a user's project ignores")]
        [TestCase(true, false, false, TestName = "MOCAP_MOCAPCTL set outside the repository: fails")]
        [TestCase(false, true, false, TestName = "Inside the repository without MOCAP_MOCAPCTL: fails")]
        [TestCase(true, true, false, TestName = "scripts/test.sh in the repository: fails")]
        public void TheOutcomeFollowsTheEnvironment(bool mocapctlVariableSet, bool repositoryRootFound, bool ignored)
        {
            var expected = ignored ? AbsenceOutcome.Ignore : AbsenceOutcome.Fail;
            Assert.AreEqual(expected, RepositoryAbsence.Decide(mocapctlVariableSet, repositoryRootFound));
        }

        [Test]
        public void InAUsersProjectTheTestIsIgnoredWithTheReason()
        {
            var result = TestPaths.AbsenceResult("mocapctl not found", false, false);
            Assert.IsInstanceOf<IgnoreException>(result);
            Assert.AreEqual("needs the com.mocap.imu repository's engine build: mocapctl not found", result.Message);
        }

        [TestCase(true, false)]
        [TestCase(false, true)]
        public void WhereTheRepositoryIsExpectedTheTestFails(bool mocapctlVariableSet, bool repositoryRootFound)
        {
            var result = TestPaths.AbsenceResult("mocapctl not found", mocapctlVariableSet, repositoryRootFound);
            Assert.IsInstanceOf<AssertionException>(result);
            Assert.AreEqual("mocapctl not found", result.Message);
        }

        [Test]
        public void ThisRunIsInTheRepositorySoAnAbsenceFails()
        {
            // About this repository's own runs: a user's project ignores it like the engine tests.
            TestPaths.RequireRepoRoot();
            var result = TestPaths.AbsenceResult("the native library was not found");
            Assert.IsInstanceOf<AssertionException>(result, "an absence inside the repository must fail, never be ignored");
        }
    }
}
