"""Tests of scripts/wine_test_launcher.sh, ctest's launcher for the Windows test programs.

A stand-in for the wine binary (MOCAP_WINE_BINARY) plays the ways a start can go: a program
that never got to print (started again, at most three starts in all), one that printed and
failed (a real failure: never started again), one whose host loader aborted at teardown (started
again), and one that passes."""

import os
import subprocess
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent.parent
LAUNCHER = REPO / "scripts" / "wine_test_launcher.sh"


def fake_wine(tmp_path, body):
    """A 'wine' that counts its starts in tmp_path/starts and then runs body (bash)."""
    script = tmp_path / "fake-wine"
    script.write_text("#!/usr/bin/env bash\n"
                      f'echo "$*" >> "{tmp_path}/starts"\n'
                      f'n=$(wc -l < "{tmp_path}/starts")\n' + body + "\n")
    script.chmod(0o755)
    return script


def launch(tmp_path, body, *args):
    env = dict(os.environ, MOCAP_WINE_BINARY=str(fake_wine(tmp_path, body)))
    result = subprocess.run([str(LAUNCHER), "prog.exe", *args], capture_output=True, text=True,
                            env=env, timeout=30)
    starts = (tmp_path / "starts").read_text().splitlines()
    return result, starts


def test_a_silent_failed_start_is_started_again_with_the_same_arguments(tmp_path):
    result, starts = launch(tmp_path, 'if [ "$n" -lt 2 ]; then exit 3; fi\n'
                                      'echo "[==========] Running 1 test"; exit 0',
                            "--gtest_filter=OscEncoder.NestedBundles")
    assert result.returncode == 0
    assert starts == ["prog.exe --gtest_filter=OscEncoder.NestedBundles"] * 2
    assert "[==========] Running 1 test" in result.stdout
    assert "prog.exe exited 3 under Wine before printing anything (start 1 of 3)" in result.stderr


def test_a_program_that_printed_and_failed_is_a_failure_and_not_started_again(tmp_path):
    result, starts = launch(tmp_path, 'echo "[  FAILED  ] OscEncoder.NestedBundles"; exit 1')
    assert result.returncode == 1
    assert len(starts) == 1
    assert "[  FAILED  ] OscEncoder.NestedBundles" in result.stdout
    assert "under Wine before printing anything" not in result.stderr


LOADER_ABORT = ("Inconsistency detected by ld.so: dl-fini.c: 87: _dl_fini: Assertion "
                "`ns != LM_ID_BASE || i == nloaded' failed!")


def loader_abort_file(tmp_path):
    """The abort message in a file, so its quotes and backticks reach stderr as they are."""
    path = tmp_path / "loader-abort"
    path.write_text(LOADER_ABORT + "\n")
    return path


def test_a_host_loader_abort_at_teardown_is_started_again(tmp_path):
    abort = loader_abort_file(tmp_path)
    result, starts = launch(tmp_path, 'echo "[  PASSED  ] 1 test."\n'
                                      f'if [ "$n" -lt 2 ]; then cat "{abort}" >&2; exit 127; fi\n'
                                      "exit 0")
    assert result.returncode == 0
    assert len(starts) == 2
    assert "after Wine's host loader aborted at process teardown (start 1 of 3)" in result.stderr


def test_a_host_loader_abort_every_time_stays_a_failure(tmp_path):
    abort = loader_abort_file(tmp_path)
    result, starts = launch(tmp_path, f'echo "[  PASSED  ] 1 test."; cat "{abort}" >&2; exit 127')
    assert result.returncode == 127
    assert len(starts) == 3


def test_three_silent_failures_give_the_last_exit_status(tmp_path):
    result, starts = launch(tmp_path, "exit 5")
    assert result.returncode == 5
    assert len(starts) == 3
    assert "(start 3 of 3)" in result.stderr


def test_a_silent_success_is_passed_on_once(tmp_path):
    result, starts = launch(tmp_path, "exit 0")
    assert result.returncode == 0
    assert len(starts) == 1


def test_a_timeout_stop_shows_what_the_program_printed_and_stops_it(tmp_path):
    body = f'echo "[ RUN      ] Slow.Test"; echo $$ > "{tmp_path}/pid"; exec sleep 60'
    env = dict(os.environ, MOCAP_WINE_BINARY=str(fake_wine(tmp_path, body)))
    launcher = subprocess.Popen([str(LAUNCHER), "prog.exe"], stdout=subprocess.PIPE, text=True,
                                env=env)
    pid_file = tmp_path / "pid"
    deadline = time.monotonic() + 10
    while not pid_file.exists() or not pid_file.read_text().strip():
        assert time.monotonic() < deadline, "the stand-in program never started"
        time.sleep(0.05)
    launcher.terminate()
    stdout, _ = launcher.communicate(timeout=10)
    assert launcher.returncode == 143
    assert "[ RUN      ] Slow.Test" in stdout
    program = int(pid_file.read_text())
    deadline = time.monotonic() + 5
    while Path(f"/proc/{program}").exists() and b"zombie" not in _state(program):
        assert time.monotonic() < deadline, "the program outlived its launcher"
        time.sleep(0.05)


def _state(pid):
    try:
        return Path(f"/proc/{pid}/status").read_bytes().lower()
    except OSError:
        return b"zombie"
