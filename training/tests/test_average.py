"""Weight averaging (training.average): the mean of checkpoints is a loadable network whose
parameters are the weighted means, and checkpoints that do not fit together are refused."""
import pytest
import torch

from training import average, train as tr
from training.model import ModelConfig, PoseNet


TINY = tr.SIZES["tiny"]


def _checkpoint(path, config=TINY, seed=0):
    torch.manual_seed(seed)
    net = PoseNet(config)
    torch.save({"model": net.state_dict(), "config": net.config.to_dict()}, str(path))
    return net


def test_average_of_two_checkpoints_is_the_mean_network(tmp_path):
    a = _checkpoint(tmp_path / "a.pt", seed=1)
    b = _checkpoint(tmp_path / "b.pt", seed=2)
    average.average_checkpoints([tmp_path / "a.pt", tmp_path / "b.pt"], tmp_path / "soup.pt", weights=[3, 1])
    soup = tr.load_weights(tmp_path / "soup.pt")
    sa, sb = a.state_dict(), b.state_dict()
    for k, v in soup.state_dict().items():
        if v.is_floating_point():
            torch.testing.assert_close(v, 0.75 * sa[k] + 0.25 * sb[k], rtol=0, atol=1e-6)
    assert any(not torch.equal(sa[k], sb[k]) for k in sa), "the two inputs differ"
    # the averaged network runs like any other
    x_rot = torch.eye(3).expand(1, 5, 6, 3, 3).contiguous()
    rot, vel, logits, _ = soup.forward_raw(x_rot, torch.zeros(1, 5, 6, 3))
    assert torch.isfinite(rot).all() and rot.shape[-2:] == (3, 3)
    assert torch.load(str(tmp_path / "soup.pt"), weights_only=False)["averaged_from"][1].endswith("b.pt")


def test_average_refuses_mismatched_checkpoints(tmp_path):
    _checkpoint(tmp_path / "a.pt")
    _checkpoint(tmp_path / "b.pt", config=ModelConfig(32, 48, 1, 32))
    with pytest.raises(ValueError, match="different architecture"):
        average.average_checkpoints([tmp_path / "a.pt", tmp_path / "b.pt"], tmp_path / "x.pt")
    assert not (tmp_path / "x.pt").exists()
    s = {"w": torch.ones(2)}
    with pytest.raises(ValueError, match="shape"):
        average.average_state_dicts([s, {"w": torch.ones(3)}])
    with pytest.raises(ValueError, match="different parameters"):
        average.average_state_dicts([s, {"v": torch.ones(2)}])
    with pytest.raises(ValueError, match="2 weights for 1"):
        average.average_state_dicts([s], [1, 1])
    with pytest.raises(ValueError, match=">= 0"):
        average.average_state_dicts([s, s], [1, float("nan")])


def test_average_ignores_the_training_only_dropout(tmp_path):
    from dataclasses import replace
    _checkpoint(tmp_path / "a.pt", config=replace(TINY, dropout=0.1), seed=1)
    _checkpoint(tmp_path / "b.pt", config=replace(TINY, dropout=0.3), seed=2)
    average.average_checkpoints([tmp_path / "a.pt", tmp_path / "b.pt"], tmp_path / "soup.pt")
    assert tr.load_weights(tmp_path / "soup.pt").config.dropout == 0.1   # the first one's config
    # what changes the network still has to agree
    _checkpoint(tmp_path / "c.pt", config=replace(TINY, anchored=True), seed=3)
    with pytest.raises(ValueError, match="different architecture"):
        average.average_checkpoints([tmp_path / "a.pt", tmp_path / "c.pt"], tmp_path / "x.pt")


def test_average_writes_its_output_atomically(tmp_path, monkeypatch):
    import os
    from training.errors import CommandError
    _checkpoint(tmp_path / "a.pt", seed=1)
    _checkpoint(tmp_path / "b.pt", seed=2)
    out = tmp_path / "out" / "soup.pt"
    average.average_checkpoints([tmp_path / "a.pt", tmp_path / "b.pt"], out)
    before = out.read_bytes()

    def disk_full(fd):   # the temporary is written, then the disk turns out to be full
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(CommandError, match=f"{out}: cannot write the checkpoint .No space left on device.; "
                                           f"the previous file is kept"):
        average.average_checkpoints([tmp_path / "b.pt", tmp_path / "a.pt"], out)
    assert out.read_bytes() == before and [p.name for p in out.parent.iterdir()] == ["soup.pt"]


def test_average_refuses_non_finite_weights_inputs_and_an_input_as_output(tmp_path):
    from training.errors import UsageError
    a = _checkpoint(tmp_path / "a.pt", seed=1)
    _checkpoint(tmp_path / "b.pt", seed=2)
    state = a.state_dict()
    state["lstm.weight_hh_l0"][3, 4] = float("inf")
    torch.save({"model": state, "config": a.config.to_dict()}, str(tmp_path / "inf.pt"))
    pair = [tmp_path / "a.pt", tmp_path / "b.pt"]
    with pytest.raises(UsageError, match=f"{tmp_path / 'inf.pt'}: the weights hold NaN or inf .lstm.weight_hh_l0"):
        average.average_checkpoints([tmp_path / "a.pt", tmp_path / "inf.pt"], tmp_path / "soup.pt")
    for bad in ([float("inf"), 1], [float("nan"), 1], [-1, 2], [0, 0]):
        with pytest.raises(UsageError, match="weights must be finite and >= 0 with a positive sum"):
            average.average_checkpoints(pair, tmp_path / "soup.pt", weights=bad)
    assert not (tmp_path / "soup.pt").exists()
    before = (tmp_path / "a.pt").read_bytes()
    with pytest.raises(UsageError, match="--out .*a.pt is one of the checkpoints to average"):
        average.average_checkpoints(pair, tmp_path / "." / "a.pt")
    assert (tmp_path / "a.pt").read_bytes() == before
