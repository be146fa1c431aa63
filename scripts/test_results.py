#!/usr/bin/env python3
"""Reads one test runner's results and prints the counts scripts/test.sh records.

    test_results.py --suite NAME [--allow FILE] KIND FILE

KIND and FILE:
  ctest   ctest's console output (its closing "... out of N" line and "did not run" list)
  pytest  a JUnit XML file (pytest --junitxml)
  dotnet  a TRX file (dotnet test --logger trx)
  counts  any output whose last summary line is "N passed, N failed[, N skipped]"
  units   any output whose last summary line is "N compile units ok, N failed"

Prints one line on stdout: "PASSED FAILED SKIPPED" (tests) or "OK FAILED" (units), and the
reasons behind the numbers on stderr. The numbers are honest ones:
  - a skipped test is never passed; a skip that no allow-list line (--allow) accepts is failed,
    because a skip is nearly always a dependency that is missing on this machine;
  - results that cannot be read, and a run that executed no test (or compiled no unit), are
    one failure, so a check that silently ran on nothing cannot look green.
The allow-list holds lines "suite glob (any case) | test name regex (whole name) | why the skip
is fine [| regex the runner's skip message must contain]"; the last field keeps an allowed test
from also skipping for another reason (ctest reports no message: leave it out there).
"""
import argparse
import fnmatch
import re
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path


class ResultsError(Exception):
    """The results file is missing or is not what the KIND says."""


@dataclass
class Results:
    passed: int = 0
    failed: int = 0
    skipped: list = field(default_factory=list)  # (test name, reason)
    unnamed_skips: int = 0  # a runner that reports only a count of skips


@dataclass
class AllowedSkip:
    suite_glob: str
    name_pattern: re.Pattern
    reason: str
    line: int
    message_pattern: re.Pattern = None


def read_allow_list(path):
    entries = []
    for number, raw in enumerate(Path(path).read_text().splitlines(), 1):
        text = raw.strip()
        if not text or text.startswith("#"):
            continue
        parts = [p.strip() for p in text.split("|")]
        if len(parts) not in (3, 4) or not all(parts):
            raise ResultsError(f"{path}:{number}: expected 'suite glob | test name regex | reason "
                               f"[| skip message regex]', got {raw!r}")
        try:
            patterns = [re.compile(p) for p in [parts[1]] + parts[3:]]
        except re.error as e:
            raise ResultsError(f"{path}:{number}: bad regex: {e}") from e
        entries.append(AllowedSkip(parts[0], patterns[0], parts[2], number,
                                   patterns[1] if len(patterns) > 1 else None))
    return entries


def find_allowance(entries, suite, name, message=""):
    for entry in entries:
        if (fnmatch.fnmatchcase(suite.lower(), entry.suite_glob.lower())
                and entry.name_pattern.fullmatch(name)
                and (entry.message_pattern is None or entry.message_pattern.search(message))):
            return entry
    return None


def _text(path):
    p = Path(path)
    if not p.is_file():
        raise ResultsError(f"no results file {path}")
    return p.read_text(errors="replace")


def parse_ctest(path):
    text = _text(path)
    if "No tests were found" in text:
        return Results()
    summary = re.findall(r"tests passed, (\d+) tests? failed out of (\d+)", text)
    if not summary:
        raise ResultsError(f"{path}: no ctest summary line ('... tests failed out of N')")
    failed, total = (int(n) for n in summary[-1])
    # ctest counts a skipped test (GTEST_SKIP, SKIP_RETURN_CODE, SKIP_REGULAR_EXPRESSION) and a
    # disabled one among the tests that did not fail: they are listed under "did not run".
    skipped = []
    section = text.rsplit("The following tests did not run:", 1)
    if len(section) == 2:
        for line in section[1].splitlines()[1:]:
            m = re.match(r"\s+\d+ - (\S+) \((Skipped|Disabled)\)\s*$", line)
            if not m:
                break
            skipped.append((m.group(1), m.group(2).lower()))
    return Results(passed=total - failed - len(skipped), failed=failed, skipped=skipped)


def parse_junit(path):
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ResultsError(f"{path}: not a readable JUnit XML file: {e}") from e
    results = Results()
    for case in root.iter("testcase"):
        name = ".".join(p for p in (case.get("classname", ""), case.get("name", "")) if p)
        if case.find("failure") is not None or case.find("error") is not None:
            results.failed += 1
        elif (skip := case.find("skipped")) is not None:
            # pytest writes an expected failure (xfail) as a skip too: it proves nothing either.
            results.skipped.append((name, skip.get("message", "") or skip.get("type", "")))
        else:
            results.passed += 1
    return results


TRX_NS = "{http://microsoft.com/schemas/VisualStudio/TeamTest/2010}"


def parse_trx(path):
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ResultsError(f"{path}: not a readable TRX file: {e}") from e
    class_of = {}
    for test in root.iter(TRX_NS + "UnitTest"):
        method = test.find(TRX_NS + "TestMethod")
        if method is not None:
            class_of[test.get("id")] = method.get("className", "")
    results = Results()
    for result in root.iter(TRX_NS + "UnitTestResult"):
        if result.find(TRX_NS + "InnerResults") is not None:
            continue  # a parent row of data-driven rows, which are counted themselves
        outcome = result.get("outcome", "")
        cls = class_of.get(result.get("testId"), "")
        name = f"{cls}.{result.get('testName', '')}" if cls else result.get("testName", "")
        if outcome == "Passed":
            results.passed += 1
        elif outcome in ("NotExecuted", "Inconclusive", "Ignored", "Skipped"):
            message = result.find(f"{TRX_NS}Output/{TRX_NS}ErrorInfo/{TRX_NS}Message")
            reason = message.text.strip() if message is not None and message.text else outcome
            results.skipped.append((name, reason))
        else:
            results.failed += 1
    return results


def _last_match(path, pattern, what):
    matches = [m for m in (re.match(pattern, line.strip()) for line in _text(path).splitlines()) if m]
    if not matches:
        raise ResultsError(f"{path}: no summary line '{what}'")
    return matches[-1]


def parse_counts(path):
    m = _last_match(path, r"^(\d+) passed, (\d+) failed(?:, (\d+) skipped)?$",
                    "N passed, N failed[, N skipped]")
    return Results(passed=int(m.group(1)), failed=int(m.group(2)), unnamed_skips=int(m.group(3) or 0))


def parse_units(path):
    m = _last_match(path, r"^(\d+) compile units ok, (\d+) failed$", "N compile units ok, N failed")
    return int(m.group(1)), int(m.group(2))


def tests_line(suite, results, allow_entries, log):
    failed = results.failed
    skipped = 0
    for name, reason in results.skipped:
        entry = find_allowance(allow_entries, suite, name, reason)
        if entry:
            skipped += 1
            log(f"  skipped, allowed ({entry.reason}): {name}")
        else:
            failed += 1
            log(f"  FAILED, skipped without an allow-list entry: {name} ({reason})")
    if results.unnamed_skips:
        if find_allowance(allow_entries, suite, "*"):
            skipped += results.unnamed_skips
        else:
            failed += results.unnamed_skips
            log(f"  FAILED: {results.unnamed_skips} skipped test(s) the runner does not name, "
                f"and no allow-list line for '{suite} | \\*' accepts them")
    ran = results.passed + results.failed + len(results.skipped) + results.unnamed_skips
    if ran == 0:
        log("  FAILED: the suite executed no test")
        failed += 1
    return f"{results.passed} {failed} {skipped}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--suite", required=True, help="the suite's name in the summary")
    ap.add_argument("--allow", help="the allow-list of skips (scripts/allowed_skips.txt)")
    ap.add_argument("kind", choices=["ctest", "pytest", "dotnet", "counts", "units"])
    ap.add_argument("file")
    args = ap.parse_args(argv)

    def log(message):
        print(message, file=sys.stderr)

    try:
        if args.kind == "units":
            ok, failed = parse_units(args.file)
            if ok + failed == 0:
                log("  FAILED: the check compiled no unit")
                failed = 1
            print(f"{ok} {failed}")
            return 0
        parse = {"ctest": parse_ctest, "pytest": parse_junit, "dotnet": parse_trx,
                 "counts": parse_counts}[args.kind]
        results = parse(args.file)
        allow_entries = read_allow_list(args.allow) if args.allow else []
    except ResultsError as e:
        log(f"  FAILED: {e}")
        print("0 1" if args.kind == "units" else "0 1 0")
        return 0
    print(tests_line(args.suite, results, allow_entries, log))
    return 0


if __name__ == "__main__":
    sys.exit(main())
