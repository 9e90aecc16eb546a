"""The danger-raising join (`services/vision/danger_raise.py`): a second verifier may raise the X and TRIANGLE
probabilities, never the O. Checked in closed form on two small hand-built ONNX networks (`test_ensemble`'s), and on
the committed model joined with itself, which must judge exactly as it does alone."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import onnx
import pytest
from typer.testing import CliRunner

from services.vision.danger_raise import RAISED_KEY, raise_join
from services.vision.danger_raise import main as raise_main
from services.vision.ensemble import SHAPE_NAMES
from services.vision.verifier import MODEL_PATH, N_CLAIM, PATCH, SHAPES, Verifier, claim
from tests.vision.test_ensemble import _net, _probs, _save


@pytest.mark.parametrize("shapes", [("X", "TRIANGLE"), ("X",), ("TRIANGLE",)])
def test_the_raised_shapes_take_the_higher_and_the_rest_stays_the_bases(tmp_path: Path, shapes: tuple[str, ...]) -> None:
    """Each raised shape is the higher of the two networks' probabilities; 'none', then O, pays for what was gained
    (so O is never above the base's, though the raiser is far surer of it); every row sums to one."""
    rng = np.random.default_rng(len(shapes))
    wb, wr = rng.normal(0, 2, (N_CLAIM, 4)), rng.normal(0, 2, (N_CLAIM, 4))
    cols = [k for k, s in enumerate(SHAPE_NAMES) if s in shapes]
    wr[:2, 1] += 4.0  # on X and O claims the raiser is far surer of O than the base: the join must not take that
    wr[2:, cols] += 3.0  # on TRIANGLE and loose claims it is surer of the raised shapes
    joined = _save(raise_join(_net(wb), _net(wr), shapes), tmp_path / "raised.onnx")
    rows = [0, 1, 2, 3, 3, 1, 0, 2]
    crops = rng.integers(0, 256, (len(rows), 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.eye(N_CLAIM, dtype=np.float32)[np.array(rows)]
    pb, pr = _probs(wb, crops, claims), _probs(wr, crops, claims)
    want = pb.copy()
    want[:, cols] = np.maximum(pb[:, cols], pr[:, cols])
    gained = (want[:, cols] - pb[:, cols]).sum(axis=1)
    want[:, 3] = np.maximum(pb[:, 3] - gained, 0.0)
    want[:, 1] = np.maximum(pb[:, 1] - np.maximum(gained - pb[:, 3], 0.0), 0.0)
    want /= want.sum(axis=1, keepdims=True)
    got = joined.probabilities(crops, claims)
    assert np.allclose(got, want, atol=1e-5)
    assert np.allclose(got.sum(axis=1), 1.0, atol=1e-5)
    assert (got[:, 1] <= pb[:, 1] + 1e-6).all() and (pr[:, 1] > pb[:, 1] + 0.1).any()
    # the danger shapes together never lose (one may, to the other, where both were raised past one in all)
    assert (got[:, cols].sum(axis=1) >= pb[:, cols].sum(axis=1) - 1e-6).all() and (pr[:, cols] > pb[:, cols] + 0.1).any()
    assert joined.thresholds == (0.25, 0.8, 0.8)
    assert onnx.load(str(tmp_path / "raised.onnx")).metadata_props[-1].value == ",".join(shapes)


def test_the_committed_model_raised_by_itself_judges_as_it_does_alone(tmp_path: Path) -> None:
    """The committed model (itself raised since round vision68b) as both inputs: the same probabilities on every kind
    of row, its metadata kept and the raised shapes named; an unknown shape is refused, and so is writing over the
    committed file; the command refuses a raised model as the raiser (give the raiser's own joined model)."""
    model = onnx.load(str(MODEL_PATH))
    same = _save(raise_join(model, model, ("X", "TRIANGLE")), tmp_path / "same.onnx")
    committed = Verifier.load()
    rng = np.random.default_rng(3)
    crops = rng.integers(0, 256, (12, 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.stack([claim([None, *SHAPES][k % 4]) for k in range(12)])
    assert np.allclose(same.probabilities(crops, claims), committed.probabilities(crops, claims), atol=1e-6)
    assert (same.thresholds, same.loose_thresholds) == (committed.thresholds, committed.loose_thresholds)
    meta = {p.key: p.value for p in onnx.load(str(tmp_path / "same.onnx")).metadata_props}
    assert meta[RAISED_KEY] == "X,TRIANGLE" and meta["veto_shapes"] == "X"  # the outer join's, then the base's
    for bad in (("X", "STAR"), ("O",), ()):
        with pytest.raises(ValueError, match="shapes"):
            raise_join(model, model, bad)
    runner = CliRunner()
    bad = runner.invoke(_app(), [str(MODEL_PATH), str(MODEL_PATH), "--shapes", "X,STAR", "--out", str(tmp_path / "b")])
    assert bad.exit_code != 0 and "STAR" in bad.output
    over = runner.invoke(_app(), [str(MODEL_PATH), str(MODEL_PATH), "--out", str(MODEL_PATH)])
    assert over.exit_code != 0 and "committed" in over.output
    twice = runner.invoke(_app(), [str(MODEL_PATH), str(MODEL_PATH), "--out", str(tmp_path / "twice.onnx")])
    assert twice.exit_code != 0 and "RAISER" in twice.output and "already" in twice.output


def test_what_the_raiser_repeats_of_the_base_is_run_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The committed model's raiser carries the base's veto (`ensemble.share`, stop 117): the joined graph holds and
    runs that network once, and judges bit for bit as the join that runs it twice (the file stop 116 committed), on
    loose rows and claimed ones."""
    import services.vision.danger_raise as danger_raise
    from services.vision.ensemble import MAIN, RAISER, VETO, join, network, unraise

    glossy = Path(__file__).parents[2] / "docs/experiments/models/vision67_glossy_proposals.onnx"
    committed = onnx.load(str(MODEL_PATH))
    base = unraise(committed)
    raiser = join(network(onnx.load(str(glossy)), MAIN), network(committed, VETO), loose_x=0.1)
    shared = raise_join(base, raiser, ("X",))
    monkeypatch.setattr(danger_raise, "share", lambda model, role: model)
    twice = raise_join(base, raiser, ("X",))
    convs = [sum(n.op_type == "Conv" for n in m.graph.node) for m in (shared, twice)]
    assert convs == [9, 12]  # three networks of three convolutions, not four
    assert not any(n.output[0].startswith(RAISER + VETO) for n in shared.graph.node)
    assert len(shared.SerializeToString()) < 0.8 * len(twice.SerializeToString())
    assert hashlib.sha256(twice.SerializeToString()).hexdigest().startswith("49823c1e")  # stop 116's committed file
    rng = np.random.default_rng(5)
    crops = rng.integers(0, 256, (40, 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.stack([claim([None, *SHAPES][k % 4]) for k in range(40)])
    one, two = _save(shared, tmp_path / "shared.onnx"), _save(twice, tmp_path / "twice.onnx")
    assert np.array_equal(one.probabilities(crops, claims), two.probabilities(crops, claims))
    assert np.array_equal(one.probabilities(crops[::4], claims[::4]), two.probabilities(crops[::4], claims[::4]))


def _app() -> object:
    import typer

    app = typer.Typer()
    app.command()(raise_main)
    return app
