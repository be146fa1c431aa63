"""scripts/test_results.py, the reader behind scripts/test.sh's counts: skips are never passes,
an unlisted skip is a failure, and a run of nothing is a failure."""

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "test_results.py"
ALLOWED_SKIPS = REPO / "scripts" / "allowed_skips.txt"

sys.path.insert(0, str(REPO / "scripts"))
import test_results  # noqa: E402


def run(tmp_path, kind, text, suite="engine (release)", allow=""):
    results = tmp_path / "results"
    results.write_text(text)
    allow_file = tmp_path / "allow.txt"
    allow_file.write_text(allow)
    done = subprocess.run([sys.executable, str(SCRIPT), "--suite", suite, "--allow", str(allow_file),
                           kind, str(results)], capture_output=True, text=True, check=True)
    return done.stdout.strip(), done.stderr


CTEST_WITH_SKIP = """\
    1/3 Test #1: Math.Adds .......................   Passed    0.01 sec
    2/3 Test #2: Vmc.Ipv6Loopback ................***Skipped   0.01 sec
    3/3 Test #3: Math.Fails ......................***Failed    0.01 sec

67% tests passed, 1 tests failed out of 3

Total Test time (real) =   0.05 sec

The following tests did not run:
\t  2 - Vmc.Ipv6Loopback (Skipped)

The following tests FAILED:
\t  3 - Math.Fails (Failed)
"""


def test_ctest_skip_is_not_a_pass_and_fails_when_not_allowed(tmp_path):
    out, err = run(tmp_path, "ctest", CTEST_WITH_SKIP)
    assert out == "1 2 0"
    assert "Vmc.Ipv6Loopback" in err and "allow-list" in err


def test_ctest_skip_on_the_allow_list_is_counted_as_skipped(tmp_path):
    out, err = run(tmp_path, "ctest", CTEST_WITH_SKIP,
                   allow="engine (*) | Vmc\\.Ipv6.* | containers may lack IPv6\n")
    assert out == "1 1 1"
    assert "containers may lack IPv6" in err


def test_allow_list_matches_the_whole_name_and_the_suite(tmp_path):
    out, _ = run(tmp_path, "ctest", CTEST_WITH_SKIP, allow="engine (*) | Vmc | partial name\n")
    assert out == "1 2 0"
    out, _ = run(tmp_path, "ctest", CTEST_WITH_SKIP, allow="dotnet* | Vmc\\..* | other suite\n")
    assert out == "1 2 0"


def test_an_allowed_test_skipping_for_another_reason_fails(tmp_path):
    allow = ("python* | training\\.tests\\.test_ort\\.test_run_onnx | a runtime with CUDA has nothing "
             "to refuse | has CUDA\n")
    out, err = run(tmp_path, "pytest", JUNIT, suite="python (training)", allow=allow)
    assert out == "1 4 0", "the skip message 'ONNX Runtime not fetched' is not the allowed one"
    allow = allow.replace("has CUDA", "not fetched")
    out, err = run(tmp_path, "pytest", JUNIT, suite="python (training)", allow=allow)
    assert out == "1 3 1"


def test_ctest_no_tests_found_and_no_summary_are_failures(tmp_path):
    out, err = run(tmp_path, "ctest", "Test project /x\nNo tests were found!!!\n")
    assert out == "0 1 0" and "executed no test" in err
    out, err = run(tmp_path, "ctest", "make: *** [all] Error 2\n")
    assert out == "0 1 0" and "no ctest summary" in err


JUNIT = """<?xml version="1.0" encoding="utf-8"?><testsuites><testsuite name="pytest">
<testcase classname="training.tests.test_ort" name="test_round_trip" time="0.1"/>
<testcase classname="training.tests.test_ort" name="test_run_onnx" time="0.0">
  <skipped type="pytest.skip" message="ONNX Runtime not fetched">x</skipped></testcase>
<testcase classname="training.tests.test_cli" name="test_known_bug" time="0.0">
  <skipped type="pytest.xfail" message="known bug"/></testcase>
<testcase classname="training.tests.test_cli" name="test_broken" time="0.0">
  <failure message="assert 1 == 2"/></testcase>
<testcase classname="training.tests.test_cli" name="" time="0.0"><error message="collection"/></testcase>
</testsuite></testsuites>"""


def test_pytest_skips_and_xfails_are_not_passes(tmp_path):
    out, err = run(tmp_path, "pytest", JUNIT, suite="python (training)")
    assert out == "1 4 0"
    assert "training.tests.test_ort.test_run_onnx" in err
    assert "training.tests.test_cli.test_known_bug" in err


def test_pytest_that_collected_nothing_fails(tmp_path):
    out, err = run(tmp_path, "pytest", '<testsuites><testsuite name="pytest" tests="0"/></testsuites>')
    assert out == "0 1 0" and "executed no test" in err
    out, err = run(tmp_path, "pytest", "not xml at all")
    assert out == "0 1 0" and "JUnit" in err


TRX = """<?xml version="1.0" encoding="utf-8"?>
<TestRun xmlns="http://microsoft.com/schemas/VisualStudio/TeamTest/2010">
<Results>
 <UnitTestResult testId="a" testName="Writes" outcome="Passed"/>
 <UnitTestResult testId="b" testName="NeedsDevFull" outcome="NotExecuted">
  <Output><ErrorInfo><Message>needs /dev/full</Message></ErrorInfo></Output></UnitTestResult>
 <UnitTestResult testId="c" testName="RefusesCuda" outcome="NotExecuted"/>
 <UnitTestResult testId="d" testName="Breaks" outcome="Failed"/>
</Results>
<TestDefinitions>
 <UnitTest id="a" name="Writes"><TestMethod className="Mocap.RecordingTests" name="Writes"/></UnitTest>
 <UnitTest id="b" name="NeedsDevFull"><TestMethod className="Mocap.RecordingTests" name="NeedsDevFull"/></UnitTest>
 <UnitTest id="c" name="RefusesCuda"><TestMethod className="Mocap.SolverTests" name="RefusesCuda"/></UnitTest>
 <UnitTest id="d" name="Breaks"><TestMethod className="Mocap.SolverTests" name="Breaks"/></UnitTest>
</TestDefinitions></TestRun>"""


def test_dotnet_not_executed_is_a_skip_named_by_class(tmp_path):
    out, err = run(tmp_path, "dotnet", TRX, suite="dotnet (C# core)",
                   allow="dotnet* | Mocap\\.SolverTests\\.RefusesCuda | a CUDA runtime has nothing to refuse\n")
    assert out == "1 2 1"
    assert "Mocap.RecordingTests.NeedsDevFull (needs /dev/full)" in err


def test_counts_line_with_and_without_skips(tmp_path):
    assert run(tmp_path, "counts", "x\n12 passed, 1 failed\n")[0] == "12 1 0"
    out, err = run(tmp_path, "counts", "3 passed, 0 failed, 2 skipped\n")
    assert out == "3 2 0" and "does not name" in err
    out, _ = run(tmp_path, "counts", "3 passed, 0 failed, 2 skipped\n", suite="glibc",
                 allow="glibc | \\* | this check may skip\n")
    assert out == "3 0 2"
    assert run(tmp_path, "counts", "0 passed, 0 failed\n")[0] == "0 1 0"
    assert run(tmp_path, "counts", "garbage\n")[0] == "0 1 0"


def test_units_count_compile_units_and_zero_units_fail(tmp_path):
    assert run(tmp_path, "units", "a.c:\nerror\n31 compile units ok, 1 failed\n")[0] == "31 1"
    out, err = run(tmp_path, "units", "0 compile units ok, 0 failed\n")
    assert out == "0 1" and "compiled no unit" in err
    assert run(tmp_path, "units", "")[0] == "0 1"


def test_a_malformed_allow_list_fails_the_suite(tmp_path):
    out, err = run(tmp_path, "ctest", CTEST_WITH_SKIP, allow="engine | only two fields\n")
    assert out == "0 1 0" and "expected 'suite glob" in err


def test_the_projects_allow_list_parses_and_gives_every_entry_a_reason():
    entries = test_results.read_allow_list(ALLOWED_SKIPS)
    assert entries, "scripts/allowed_skips.txt has no entry"
    for entry in entries:
        assert len(entry.reason.split()) >= 4, f"line {entry.line}: give a real reason"


def test_missing_results_file_is_a_failure(tmp_path):
    done = subprocess.run([sys.executable, str(SCRIPT), "--suite", "x", "dotnet", str(tmp_path / "none.trx")],
                          capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "0 1 0"


@pytest.mark.parametrize("kind", ["ctest", "pytest", "dotnet", "counts", "units"])
def test_every_kind_fails_on_an_empty_file(tmp_path, kind):
    out, _ = run(tmp_path, kind, "")
    assert out in ("0 1 0", "0 1")
