"""The PlayMode capture fixture committed in the package equals a fresh regeneration by
scripts/make_test_fixtures.sh, byte for byte, and stays small."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "Packages" / "com.mocap.imu" / "Tests" / "Runtime" / "Fixtures"
SCRIPT = REPO / "scripts" / "make_test_fixtures.sh"
FILES = ["walk.cap", "walk.truth.csv"]


def _mocapctl():
    env = os.environ.get("MOCAP_MOCAPCTL")
    if env:
        return env
    built = REPO / "build" / "engine" / "mocapctl"
    return str(built) if built.exists() else shutil.which("mocapctl")


def test_fixture_is_committed_and_small():
    total = 0
    for name in FILES:
        path = FIXTURES / name
        assert path.exists(), f"{path} is missing: run scripts/make_test_fixtures.sh"
        total += path.stat().st_size
    assert total < 1_000_000, f"the fixtures take {total} bytes; keep them under 1 MB"
    head = (FIXTURES / "walk.cap").read_bytes()[:24]
    assert head[:8] == b"MOCAPRAW"
    assert head[16:24] == bytes(8), "created_ns must be 0 so the fixture is reproducible"


def test_fixture_regenerates_byte_for_byte(tmp_path):
    mocapctl = _mocapctl()
    if not mocapctl or not Path(mocapctl).exists():
        pytest.skip("mocapctl not built: set MOCAP_MOCAPCTL or build build/engine")
    env = dict(os.environ, MOCAP_MOCAPCTL=mocapctl)
    subprocess.run(["bash", str(SCRIPT), str(tmp_path)], check=True, env=env, capture_output=True)
    for name in FILES:
        fresh = (tmp_path / name).read_bytes()
        committed = (FIXTURES / name).read_bytes()
        assert fresh == committed, f"{name} differs from a fresh regeneration: run scripts/make_test_fixtures.sh"
