"""The joined verifier (`services/vision/ensemble.py`): a loose candidate is named X only if a second network
agrees; every other row and class is the first network's. Checked on two small hand-built ONNX networks with
known outputs, and on the committed model, which no longer takes a filled star on a card for an X."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper

from schemas.messages import Shape
from services.vision.detector import MarkDetector
from services.vision.ensemble import SHAPE_NAMES, join, network, parse_capped, part
from services.vision.verifier import INPUT_FORMAT, MODEL_PATH, N_CLAIM, PATCH, Verifier


def _net(weights: np.ndarray, loose: str = "0.5,0.95,0.9") -> Any:
    """A verifier-shaped network whose logits are `claim @ weights` plus the mean crop brightness on 'none': its
    probabilities are known in closed form (`_probs`)."""
    w = helper.make_tensor("w", TensorProto.FLOAT, list(weights.shape), weights.astype(np.float32).ravel().tolist())
    onehot_none = helper.make_tensor("none", TensorProto.FLOAT, [1, 4], [0.0, 0.0, 0.0, 1.0])
    axes = helper.make_tensor("axes", TensorProto.INT64, [3], [1, 2, 3])
    nodes = [
        helper.make_node("MatMul", ["claim", "w"], ["logits0"]),
        helper.make_node("ReduceMean", ["crops", "axes"], ["bright"], keepdims=0),  # (n,)
        helper.make_node("Unsqueeze", ["bright", "one"], ["bright2"]),
        helper.make_node("Mul", ["bright2", "none"], ["extra"]),
        helper.make_node("Add", ["logits0", "extra"], ["logits"]),
        helper.make_node("Softmax", ["logits"], ["probabilities"], axis=1),
    ]
    graph = helper.make_graph(
        nodes,
        "tiny",
        [
            helper.make_tensor_value_info("crops", TensorProto.FLOAT, ["n", 3, PATCH, PATCH]),
            helper.make_tensor_value_info("claim", TensorProto.FLOAT, ["n", N_CLAIM]),
        ],
        [helper.make_tensor_value_info("probabilities", TensorProto.FLOAT, ["n", 4])],
        [w, onehot_none, axes, helper.make_tensor("one", TensorProto.INT64, [1], [1])],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 9
    for key, value in (("input_format", INPUT_FORMAT), ("thresholds", "0.25,0.8,0.8"), ("loose_thresholds", loose)):
        model.metadata_props.add(key=key, value=value)
    return model


def _probs(weights: np.ndarray, crops: np.ndarray, claims: np.ndarray) -> np.ndarray:
    logits = claims @ weights
    logits[:, 3] += (crops.astype(np.float32) / 255.0).mean(axis=(1, 2, 3))
    e = np.exp(logits - logits.max(axis=1, keepdims=True))
    return e / e.sum(axis=1, keepdims=True)


def _save(model: Any, path: Path) -> Verifier:
    onnx.save(model, str(path))
    return Verifier.load(path)


@pytest.mark.parametrize("capped", [{"X": 1.0}, {"X": 1.0, "TRIANGLE": 1.0}, {"O": 1.0}, {"X": 1.0, "TRIANGLE": 4.0}])
@pytest.mark.parametrize("rows", [[0, 3, 1, 3, 2, 0, 3], [0, 1, 2, 0], [3, 3, 3], []])
def test_loose_rows_take_the_lower_of_each_capped_shape_and_all_else_is_the_first_network(
    tmp_path: Path, rows: list[int], capped: dict[str, float]
) -> None:
    rng = np.random.default_rng(len(rows))
    wm, wv = rng.normal(0, 2, (N_CLAIM, 4)), rng.normal(0, 2, (N_CLAIM, 4))
    cols = [k for k, s in enumerate(SHAPE_NAMES) if s in capped]
    wm[3, cols], wv[3, cols] = 3.0, -3.0  # on loose rows the first network leans to the capped shapes, the second not
    joined = _save(join(_net(wm), _net(wv), loose_x=0.1, capped=capped), tmp_path / "joined.onnx")
    crops = rng.integers(0, 256, (len(rows), 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.eye(N_CLAIM, dtype=np.float32)[np.array(rows, int)].reshape(len(rows), N_CLAIM)
    pm, pv = _probs(wm, crops, claims), _probs(wv, crops, claims)
    want = pm.copy()
    loose = np.array(rows, int) == 3
    for k in cols:
        want[loose, k] = np.minimum(pm[loose, k], capped[SHAPE_NAMES[k]] * pv[loose, k])
        want[loose, 3] += pm[loose, k] - want[loose, k]  # what a capped shape lost goes to 'none'
    got = joined.probabilities(crops, claims)
    assert got.shape == (len(rows), 4)
    assert np.allclose(got, want, atol=1e-5)
    assert np.allclose(got.sum(axis=1), 1.0, atol=1e-5)
    for k in cols:
        assert (got[loose, k] < pm[loose, k] - 0.1).all()  # the veto cut every loose row's capped shapes
    onnx_meta = {p.key: p.value for p in onnx.load(str(tmp_path / "joined.onnx")).metadata_props}
    assert parse_capped(onnx_meta["veto_shapes"]) == capped


def test_capped_shapes_the_join_cannot_use_are_refused_and_the_text_form_is_read() -> None:
    w = np.zeros((N_CLAIM, 4))
    with pytest.raises(ValueError, match="capped shapes"):
        join(_net(w), _net(w), loose_x=0.1, capped={"SQUARE": 1.0})
    with pytest.raises(ValueError, match="capped shapes"):
        join(_net(w), _net(w), loose_x=0.1, capped={})
    with pytest.raises(ValueError, match="capped shapes"):
        join(_net(w), _net(w), loose_x=0.1, capped={"X": 0.0})
    with pytest.raises(ValueError, match="'nine' is not a scale"):
        parse_capped("X,TRIANGLE*nine")
    assert parse_capped("X,TRIANGLE*9") == {"X": 1.0, "TRIANGLE": 9.0}


def test_the_joined_model_keeps_the_first_networks_thresholds_but_the_loose_x(tmp_path: Path) -> None:
    w = np.zeros((N_CLAIM, 4))
    joined = _save(join(_net(w, loose="0.5,0.95,0.9"), _net(w), loose_x=0.2), tmp_path / "joined.onnx")
    assert joined.thresholds == (0.25, 0.8, 0.8)
    assert joined.loose_thresholds == (0.2, 0.95, 0.9)


def test_each_network_comes_back_out_of_a_joined_model(tmp_path: Path) -> None:
    """`part` undoes `join`: each network alone gives its own probabilities, and joining the two parts again gives
    the joined model's, so a new main network can be joined to a committed veto (round vision24)."""
    rng = np.random.default_rng(7)
    wm, wv = rng.normal(0, 2, (N_CLAIM, 4)), rng.normal(0, 2, (N_CLAIM, 4))
    joined = join(_net(wm), _net(wv), loose_x=0.1)
    crops = rng.integers(0, 256, (9, 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.eye(N_CLAIM, dtype=np.float32)[rng.integers(0, N_CLAIM, 9)]
    main, veto = part(joined, "main_"), part(joined, "veto_")
    assert np.allclose(_save(main, tmp_path / "m.onnx").probabilities(crops, claims), _probs(wm, crops, claims), atol=1e-5)
    assert np.allclose(_save(veto, tmp_path / "v.onnx").probabilities(crops, claims), _probs(wv, crops, claims), atol=1e-5)
    again = _save(join(network(joined, "main_"), network(joined, "veto_"), loose_x=0.1), tmp_path / "again.onnx")
    want = _save(joined, tmp_path / "joined.onnx").probabilities(crops, claims)
    assert np.array_equal(again.probabilities(crops, claims), want)
    assert network(main, "main_") is main  # a plain network is itself


def test_the_committed_verifier_is_its_base_raised_by_the_glossy_network(tmp_path: Path) -> None:
    """Since round vision68b the committed model is a danger-raised join (`danger_raise.py`): its base is two networks
    joined (main and veto: joined again from its parts it judges exactly as it does), and the committed file is remade
    byte for byte from that base and round vision68b's raiser, the glossy network in docs/experiments/models/ joined
    to the base's veto; `network` takes the base's networks out of it, as `training --init` and `ensemble` do."""
    from services.vision.danger_raise import raise_join
    from services.vision.ensemble import MAIN, VETO, unraise

    committed = onnx.load(str(MODEL_PATH))
    base = unraise(committed)
    again = _save(join(part(base, MAIN), part(base, VETO), loose_x=0.1), tmp_path / "again.onnx")
    rng = np.random.default_rng(3)
    crops = rng.integers(0, 256, (16, 3, PATCH, PATCH)).astype(np.uint8)
    claims = np.eye(N_CLAIM, dtype=np.float32)[np.arange(16) % N_CLAIM]
    assert np.array_equal(again.probabilities(crops, claims), _save(base, tmp_path / "base.onnx").probabilities(crops, claims))
    glossy = onnx.load(str(Path(__file__).parents[2] / "docs/experiments/models/vision67_glossy_proposals.onnx"))
    raiser = join(network(glossy, MAIN), network(committed, VETO), loose_x=0.1)
    assert raise_join(base, raiser, ("X",)).SerializeToString() == MODEL_PATH.read_bytes()
    assert network(committed, MAIN).graph.SerializeToString() == part(base, MAIN).graph.SerializeToString()
    with pytest.raises(ValueError, match="not a danger-raised"):
        unraise(base)


def test_part_refuses_what_is_not_a_joined_model() -> None:
    with pytest.raises(ValueError, match="not a joined verifier"):
        part(_net(np.zeros((N_CLAIM, 4))), "main_")
    with pytest.raises(ValueError, match="role"):
        part(join(_net(np.zeros((N_CLAIM, 4))), _net(np.zeros((N_CLAIM, 4))), 0.1), "other_")


def test_models_of_other_opsets_are_refused() -> None:
    w = np.zeros((N_CLAIM, 4))
    other = _net(w)
    other.opset_import[0].version = 17
    with pytest.raises(ValueError, match="opsets differ"):
        join(_net(w), other, loose_x=0.1)


def _star_or_x(shape: Shape | None, seed: int) -> np.ndarray:
    """A filled five- or six-pointed star (None) or an X on a white card on a grey wall."""
    rng = np.random.default_rng(seed)
    img = np.full((480, 640), 120, np.uint8)
    w, h = int(rng.uniform(120, 220)), int(rng.uniform(120, 220))
    x0, y0 = int(rng.uniform(60, 640 - w - 60)), int(rng.uniform(60, 480 - h - 60))
    cv2.rectangle(img, (x0, y0), (x0 + w, y0 + h), 235, -1)
    c, r, rot = (x0 + w / 2, y0 + h / 2), rng.uniform(0.25, 0.38) * min(w, h), rng.uniform(0, 2 * math.pi)
    if shape is None:
        points = int(rng.choice([5, 6]))
        pts = [
            (c[0] + rr * math.cos(rot + k * math.pi / points), c[1] + rr * math.sin(rot + k * math.pi / points))
            for k, rr in enumerate([r, 0.42 * r] * points)
        ]
        cv2.fillPoly(img, [np.array(pts, np.int32)], 25, cv2.LINE_AA)
    else:
        t = max(3, int(r / 4))
        for a in (rot, rot + math.pi / 2):
            dx, dy = r * math.cos(a), r * math.sin(a)
            cv2.line(img, (int(c[0] - dx), int(c[1] - dy)), (int(c[0] + dx), int(c[1] + dy)), 25, t, cv2.LINE_AA)
    return cv2.cvtColor(cv2.GaussianBlur(img, (3, 3), 0), cv2.COLOR_GRAY2BGR)


def test_a_filled_star_on_a_card_is_not_an_x_and_an_x_still_is() -> None:
    """Main's verifier alone (before round vision23g) named each of these stars an X: a loose candidate no shape
    test claims, which the veto network, trained with stars, refuses."""
    det = MarkDetector()
    stars = [d.shape for seed in range(12) for d in det.detect(_star_or_x(None, seed))]
    xs = [[d.shape for d in det.detect(_star_or_x(Shape.X, seed))] for seed in range(12)]
    assert stars == []
    assert all(found == [Shape.X] for found in xs), xs
