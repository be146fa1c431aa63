"""Shared fixtures: procedural Daz-style BVH folders (no ../shared needed)."""
import numpy as np
import pytest

from training import procedural


@pytest.fixture(scope="session")
def fixture_dir(tmp_path_factory):
    """A CMU-like folder: bvh/NN/NN_MM.bvh + manifest.csv; returns (path, {clip: ground truth Motion})."""
    d = tmp_path_factory.mktemp("cmu_fixture")
    written = procedural.write_fixture_bvh_dir(d, n_clips=6, seed=0)
    return d, dict(written)


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
