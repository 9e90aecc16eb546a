"""Join a second verifier that may only raise the danger shapes' probabilities: `verifier.onnx`'s O stays its own.

The committed `verifier.onnx` is such a join since round vision68b: its base is the joined model of round vision45c
(main and veto, `ensemble.py`), its raiser round vision67's glossy network (kept in docs/experiments/models/) joined
to the same veto, raising the X alone. It is remade byte for byte from itself and that network:

    python -m services.vision.ensemble docs/experiments/models/vision67_glossy_proposals.onnx \\
        services/vision/verifier.onnx --out glossy-joined.onnx       # the raiser: its veto is the committed base's
    python -m services.vision.danger_raise services/vision/verifier.onnx glossy-joined.onnx --out raised.onnx

A new raiser (the glossy network came from round vision67's diagnostic fine-tune):

    pip install -e '.[train]'
    python -m services.vision.training --sheen 0.5 --sheen-shapes X,TRIANGLE --proposals 0.3 \\
        --init services/vision/verifier.onnx --epochs 2 --lr 1e-3 --out glossy.onnx   # starts from the base's main
    python -m services.vision.ensemble glossy.onnx services/vision/verifier.onnx --out glossy-joined.onnx
    python -m services.vision.danger_raise services/vision/verifier.onnx glossy-joined.onnx --out raised.onnx
    python bench/vision_bench.py --set verifier_model=raised.onnx                      # judge it

A raised model given as the base (the committed one) has its base raised instead, so a new raiser replaces the
committed one rather than adding to it; a raised model as the raiser is refused.

Why (round vision68): a network fine-tuned with glossy cards finds danger marks a lamp's reflection fades that the
base refuses, but it also names more faded round things O (letters in a line of words), and a false O lifts a
danger. Stopping is the safe direction: so the joined model gives X and TRIANGLE (`--shapes`: one or both) the higher
of the two networks' probabilities, and O and 'none' the base model's less what the raised shapes gained: first from
'none', then from O (a row whose raised shapes alone pass one is scaled back to one). So the joined model can name an
X or a triangle the base refused, never an O the base did not, and a candidate the base names O can become an X or a
triangle (a stop), not the other way round. Raising triangles too took arrow heads for triangles (round vision68);
raising the X alone passed its held-out rule (round vision68b, docs/experiments/vision-rounds.md).

The result is one ONNX graph over the verifier's usual inputs and output (`verifier.INPUT_FORMAT`): both models'
nodes on every row (their names prefixed `base_` and `raise_`), then Max, Sub, Relu and a division by the row's sum.
What the raiser repeats of the base is done once (`ensemble.share`): the committed raiser's veto is the base's, so
that network runs once on the loose rows (stop 117; the same probabilities bit for bit, 4 % more frames per
CPU-second, a 0.84 MB file instead of 1.1 MB).
Its metadata is the base model's (thresholds, loose thresholds, `veto_shapes`), with `raised_shapes` added.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from services.vision.ensemble import (
    BASE,
    RAISED,
    RAISED_KEY,
    RAISER,
    SHAPE_NAMES,
    check_same_opset,
    save_checked,
    share,
    unraise,
)
from services.vision.verifier import MODEL_PATH, SHAPES, Verifier

DANGER_SHAPES = ("X", "TRIANGLE")  # the shapes a second model may raise: a stop is the safe direction


def check_shapes(shapes: tuple[str, ...]) -> None:
    """ValueError unless `shapes` names one or both of `DANGER_SHAPES` (an O is never raised)."""
    if not shapes or any(s not in DANGER_SHAPES for s in shapes):
        raise ValueError(f"shapes {shapes!r}: one or both of {', '.join(DANGER_SHAPES)} (an O is never raised)")


def raise_join(base: Any, raiser: Any, shapes: tuple[str, ...]) -> Any:
    """The joined `onnx.ModelProto` of two verifier models (`onnx.ModelProto`, the same opset): each shape named in
    `shapes` (one or both of "X" and "TRIANGLE", `DANGER_SHAPES`) gets the higher of the two models' probabilities;
    what they gained is taken from `base`'s 'none', then from its O (each down to 0 at most); the others are `base`'s;
    the row is then divided by its sum (one, unless the raised shapes alone pass it). What the raiser's nodes repeat of
    the base's (the same veto, the same pick of the loose rows) is read from the base's (`ensemble.share`)."""
    from onnx import TensorProto, compose, helper  # type: ignore[import-not-found,unused-ignore]

    check_shapes(shapes)
    check_same_opset(base, raiser)
    b = compose.add_prefix(base, BASE, rename_inputs=False)  # both read `crops` and `claim`
    r = compose.add_prefix(raiser, RAISER, rename_inputs=False)
    pb, pr = b.graph.output[0].name, r.graph.output[0].name
    consts = [helper.make_tensor(f"d_{k}", TensorProto.INT64, [1], [k]) for k in range(len(SHAPES) + 2)]
    node = helper.make_node
    nodes, columns, gains = [], [], []
    o = SHAPE_NAMES.index("O")
    for k, shape in enumerate(SHAPE_NAMES):
        nodes.append(node("Slice", [pb, f"d_{k}", f"d_{k + 1}", "d_1"], [f"d_base_{k}"]))
        if shape not in shapes:
            columns.append("d_o_left" if k == o else f"d_base_{k}")
            continue
        nodes += [
            node("Slice", [pr, f"d_{k}", f"d_{k + 1}", "d_1"], [f"d_raise_{k}"]),
            node("Max", [f"d_base_{k}", f"d_raise_{k}"], [f"d_max_{k}"]),
            node("Sub", [f"d_max_{k}", f"d_base_{k}"], [f"d_gain_{k}"]),
        ]
        columns.append(f"d_max_{k}")
        gains.append(f"d_gain_{k}")
    n = len(SHAPES)
    nodes += [
        node("Slice", [pb, f"d_{n}", f"d_{n + 1}", "d_1"], ["d_none"]),
        node("Sum", gains, ["d_gained"]),
        node("Sub", ["d_none", "d_gained"], ["d_none_less"]),
        node("Relu", ["d_none_less"], ["d_none_left"]),
        node("Sub", ["d_gained", "d_none"], ["d_over_none"]),  # what 'none' could not pay: from O
        node("Relu", ["d_over_none"], ["d_from_o"]),
        node("Sub", [f"d_base_{o}", "d_from_o"], ["d_o_less"]),
        node("Relu", ["d_o_less"], ["d_o_left"]),
        node("Concat", [*columns, "d_none_left"], ["d_rows"], axis=1),
        node("ReduceSum", ["d_rows", "d_1"], ["d_sum"], keepdims=1),
        node("Div", ["d_rows", "d_sum"], ["probabilities"]),
    ]
    out = helper.make_tensor_value_info("probabilities", TensorProto.FLOAT, ["n", len(SHAPES) + 1])
    graph = helper.make_graph(
        list(b.graph.node) + list(r.graph.node) + nodes,
        RAISED,
        list(base.graph.input),
        [out],
        list(b.graph.initializer) + list(r.graph.initializer) + consts,
    )
    joined = helper.make_model(graph, opset_imports=base.opset_import, producer_name="services.vision.danger_raise")
    joined.ir_version = base.ir_version
    for p in base.metadata_props:
        if p.key != RAISED_KEY:
            joined.metadata_props.add(key=p.key, value=p.value)
    joined.metadata_props.add(key=RAISED_KEY, value=",".join(shapes))
    joined.doc_string = f"vision mark verifier: python -m services.vision.danger_raise BASE RAISER ({','.join(shapes)})"
    return share(joined, RAISER)  # the committed raiser's veto is the base's: run once


def main(
    base_model: Annotated[
        Path, typer.Argument(help="the model whose O and 'none' stand (of a raised model, as the committed: its base)")
    ],
    raiser_model: Annotated[
        Path, typer.Argument(help="the model that may raise the danger shapes (a joined model: its veto included)")
    ],
    shapes: Annotated[
        str, typer.Option(help="the shapes the second model may raise, comma-separated (the committed model: X)")
    ] = "X",
    out: Annotated[Path, typer.Option(help="where to write the joined model (never the committed file by default)")] = (
        Path("verifier-raised.onnx")
    ),
) -> None:
    import onnx  # type: ignore[import-not-found,unused-ignore]

    for path in (base_model, raiser_model):
        Verifier.load(path)  # refuses a file that is not a verifier model for this code's inputs
    if out.resolve() == MODEL_PATH.resolve():
        raise typer.BadParameter(f"{out}: the committed verifier is replaced only by copying a judged model over it")
    names = tuple(t.strip().upper() for t in shapes.split(",") if t.strip())
    try:
        check_shapes(names)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--shapes") from None
    base, raiser = onnx.load(str(base_model)), onnx.load(str(raiser_model))
    if raiser.graph.name == RAISED:
        raise typer.BadParameter(f"{raiser_model}: already a raised model; give the raiser itself", param_hint="RAISER")
    if base.graph.name == RAISED:  # the committed model: a new raiser replaces its own, not raises it again
        base = unraise(base)
        typer.echo(f"{base_model} is a raised model: its base is raised instead")
    # as ensemble's: two models of different opsets are refused by `raise_join`'s ValueError, not named as `--shapes`
    save_checked(raise_join(base, raiser, names), out)


if __name__ == "__main__":
    typer.run(main)
