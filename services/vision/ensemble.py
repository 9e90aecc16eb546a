"""Join two verifier networks into one model: a loose candidate is named X only if both agree.

The committed `verifier.onnx` is such a joined model (its base) raised by a second one since round vision68b
(`danger_raise.py`); given it, this command uses its base's networks (`network`).

    pip install -e '.[train]'
    python -m services.vision.training --out main.onnx                # the default recipe
    python -m services.vision.training --everyday --out everyday.onnx  # stars, check marks, clocks (round vision23)
    # the committed veto since round vision45c: --everyday --crossings 6 --proposals 0.3 (crossing strokes too)
    python -m services.vision.ensemble main.onnx everyday.onnx [--loose-x 0.1] [--out FILE]  # default: verifier.onnx
    python -m services.vision.ensemble new-main.onnx services/vision/verifier.onnx --out joined.onnx  # keep its veto
    python -m services.vision.ensemble main.onnx everyday.onnx --veto-shapes "X,TRIANGLE*9" --out FILE  # cap more

Either input may itself be a joined model: its own network in that role is taken out of it (`part`), so a new
main network can be joined to the committed veto (round vision24) without retraining the veto.

The first network (`main`) judges every row as before. The second (`veto`) runs on the loose rows only (claim
slot 'loose' set: loose candidates, parts `_split` cut off, the proposer's proposals) and gives those rows'
X probability a ceiling: it becomes the lower of the two networks' X, and what it loses goes to 'none', so a
row still sums to one. A claimed candidate, and a loose row's O and TRIANGLE, are judged by `main` alone.
Why (round vision23f, docs/experiments/vision-rounds.md): the blind generator's filled stars reach the verifier as
loose candidates that `main` names X; a network trained with stars (`--everyday`) refuses them, but used on
its own it also refused held-out marks `main` keeps.

`--veto-shapes` names the shapes the veto caps (default "X", the committed model); "X,TRIANGLE*9" also caps a loose
row's TRIANGLE by nine times the veto's, so a loose triangle needs the veto's 0.1 where `main` needs 0.9. Round
vision28 measured both on the tuning side (neither is the committed model): capping TRIANGLE takes most arrow heads
back and more true triangles with them; scaled by 9 it keeps both.

The result is one ONNX graph over the verifier's usual inputs and output (`verifier.INPUT_FORMAT`): `main`'s
nodes on every row, NonZero and GatherND to pick the loose rows for `veto`, Min and ScatterND to write their
capped shapes back. Its metadata is `main`'s, with the loose X threshold `--loose-x` (the lower of two
probabilities is lower: `main`'s own was 0.5) and `veto_shapes` (what `--veto-shapes` asked).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Annotated, Any

import typer

from services.vision.verifier import MODEL_PATH, SHAPES, Verifier

LOOSE_SLOT = len(SHAPES)  # the claim's 'loose' slot (verifier.claim)
JOINED = "verifier_loose_x_veto"  # the graph name `join` gives
MAIN, VETO = "main_", "veto_"  # the prefixes `join` gives each network's names
ROLES = (MAIN, VETO)
CAPPED_KEY = "veto_shapes"  # the metadata naming the shapes the veto caps on loose rows
RAISED = "verifier_danger_raise"  # the graph name `danger_raise.raise_join` gives (the committed model's since vision68b)
BASE, RAISER = "base_", "raise_"  # the prefixes it gives each model's names
RAISED_KEY = "raised_shapes"  # the metadata naming the shapes the raiser may raise
SHAPE_NAMES = tuple(shape.value for shape in SHAPES)  # the probability columns before 'none', as named


def part(joined: Any, role: str) -> Any:
    """One network of a joined model (`onnx.ModelProto` made by `join`) as a verifier model of its own:
    `role` "main_" or "veto_"; its names keep the prefix, its inputs are `crops` and `claim` again and its
    output is `probabilities`; the metadata is the joined model's."""
    from onnx import NodeProto, helper  # type: ignore[import-not-found,unused-ignore]

    if role not in ROLES:
        raise ValueError(f"role {role!r}: one of {ROLES}")
    g = joined.graph
    if g.name != JOINED:
        raise ValueError(f"not a joined verifier (graph {g.name!r}, expected {JOINED!r})")
    own = {f"{role}crops": "crops", f"{role}claim": "claim", f"{role}probabilities": "probabilities"}
    nodes = []
    for n in g.node:  # the network's own nodes: what they make bears its prefix (its inputs are made by `join`)
        if not any(o.startswith(role) for o in n.output) or any(own.get(o) in ("crops", "claim") for o in n.output):
            continue
        copy = NodeProto()
        copy.CopyFrom(n)  # everything as it was, but the network's own inputs and output renamed
        copy.input[:] = [own.get(i, i) for i in n.input]
        copy.output[:] = [own.get(o, o) for o in n.output]
        nodes.append(copy)
    if not nodes or "probabilities" not in nodes[-1].output:
        raise ValueError(f"no {role!r} network ending in {role}probabilities in {g.name!r}")
    graph = helper.make_graph(
        nodes, f"verifier_{role.rstrip('_')}", list(g.input), list(g.output),
        [t for t in g.initializer if t.name.startswith(role)],
    )
    model = helper.make_model(graph, opset_imports=joined.opset_import, producer_name="services.vision.ensemble")
    model.ir_version = joined.ir_version
    for p in joined.metadata_props:
        model.metadata_props.add(key=p.key, value=p.value)
    model.doc_string = f"the {role.rstrip('_')} network of a joined verifier (services.vision.ensemble.part)"
    return model


def unraise(raised: Any) -> Any:
    """The base of a danger-raised model (`onnx.ModelProto` made by `danger_raise.raise_join`) as it was: its nodes and
    weights with the prefix "base_" taken off, so a joined model is a joined model again (`part` takes its networks
    out); the metadata is the raised model's less `raised_shapes`. (The raiser is not taken out: what it shares with
    the base, `share`, is read from the base's nodes.)"""
    from onnx import NodeProto, TensorProto, helper  # type: ignore[import-not-found,unused-ignore]

    g = raised.graph
    if g.name != RAISED:
        raise ValueError(f"not a danger-raised verifier (graph {g.name!r}, expected {RAISED!r})")

    def own(name: str) -> str:  # the model's inputs `crops` and `claim` were never prefixed
        return name.removeprefix(BASE)

    nodes = []
    for n in g.node:  # the base's own nodes: all they make bears its prefix (the join's own are `d_`)
        if not any(n.output) or not all(o.startswith(BASE) for o in n.output if o):
            continue
        copy = NodeProto()
        copy.CopyFrom(n)
        copy.ClearField("name")  # the prefixing gives a nameless node the name "" (kept unset, as it was)
        if own(n.name):
            copy.name = own(n.name)
        copy.input[:] = [own(i) for i in n.input]
        copy.output[:] = [own(o) for o in n.output]
        nodes.append(copy)
    if not nodes or "probabilities" not in nodes[-1].output:
        raise ValueError(f"no {BASE!r} model ending in {BASE}probabilities in {g.name!r}")
    weights = []
    for t in g.initializer:
        if t.name.startswith(BASE):
            copy_t = TensorProto()
            copy_t.CopyFrom(t)
            copy_t.name = own(t.name)
            weights.append(copy_t)
    # the graph's own name is not kept by the join: a model with a veto network was a joined one
    joined = any(o.startswith(VETO) for n in nodes for o in n.output)
    graph = helper.make_graph(nodes, JOINED if joined else "verifier", list(g.input), list(g.output), weights)
    model = helper.make_model(graph, opset_imports=raised.opset_import, producer_name="services.vision.ensemble")
    model.ir_version = raised.ir_version
    for p in raised.metadata_props:
        if p.key != RAISED_KEY:
            model.metadata_props.add(key=p.key, value=p.value)
    model.doc_string = "the base model of a danger-raised verifier (services.vision.ensemble.unraise)"
    return model


def share(model: Any, role: str) -> Any:
    """`model` (`onnx.ModelProto` of two models joined in one graph; changed in place and returned) with what the nodes
    and weights of `role` (their names' prefix) repeat of earlier ones taken out: a weight equal in value to an earlier
    one is read from it, then a node doing what an earlier node does (op, attributes) on the same inputs is replaced by
    it. The graph computes the same, bit for bit, doing it once: a danger-raised model whose raiser carries the base's
    veto runs that network, and picks the loose rows, once (stop 117: 4 % more frames per CPU-second)."""
    from onnx import numpy_helper  # type: ignore[import-not-found,unused-ignore]

    g = model.graph
    alias: dict[str, str] = {}  # a name taken out: the earlier name read instead
    first: dict[tuple[Any, ...], str] = {}
    weights = []
    for t in g.initializer:
        key = (t.data_type, tuple(t.dims), numpy_helper.to_array(t).tobytes())
        if t.name.startswith(role) and key in first:
            alias[t.name] = first[key]
            continue
        first.setdefault(key, t.name)
        weights.append(t)
    outputs = {o.name for o in g.output}
    done: dict[tuple[Any, ...], list[str]] = {}
    nodes = []
    for n in g.node:  # in the graph's order, so a node's inputs are renamed before it is compared
        n.input[:] = [alias.get(i, i) for i in n.input]
        key = (n.domain, n.op_type, tuple(n.input), tuple(a.SerializeToString() for a in n.attribute), len(n.output))
        if key in done and all(o.startswith(role) and o not in outputs for o in n.output):
            alias.update(zip(n.output, done[key], strict=True))
            continue
        done.setdefault(key, list(n.output))
        nodes.append(n)
    del g.initializer[:]
    g.initializer.extend(weights)
    del g.node[:]
    g.node.extend(nodes)
    return model


def network(model: Any, role: str) -> Any:
    """`model` itself, or its network in `role` if it is a joined verifier; of a danger-raised one (the committed
    model since round vision68b), its base's network in `role`, so a new main network can still be joined to the
    committed veto and `training --init` still starts from the committed main network."""
    if model.graph.name == RAISED:
        model = unraise(model)
    return part(model, role) if model.graph.name == JOINED else model


def capped_text(capped: Mapping[str, float]) -> str:
    """`capped` as `--veto-shapes` takes it: "X" or "X,TRIANGLE*9" (a scale of one left out)."""
    return ",".join(s if k == 1.0 else f"{s}*{k:g}" for s, k in capped.items())


def parse_capped(text: str) -> dict[str, float]:
    """The inverse of `capped_text`; ValueError names what it could not read."""
    out = {}
    for item in text.split(","):
        shape, _, scale = item.partition("*")
        try:
            out[shape.strip()] = float(scale) if scale else 1.0
        except ValueError:
            raise ValueError(f"{text!r}: {scale!r} is not a scale (write SHAPE or SHAPE*SCALE, comma-separated)") from None
    return out


def check_capped(capped: Mapping[str, float]) -> None:
    """ValueError unless `capped` names one or more shapes, each with a scale above 0."""
    if not capped or any(shape not in SHAPE_NAMES for shape in capped) or any(k <= 0 for k in capped.values()):
        raise ValueError(f"capped shapes {dict(capped)!r}: one or more of {list(SHAPE_NAMES)}, each with a scale above 0")


def check_same_opset(first: Any, second: Any) -> None:
    """ValueError unless two models (`onnx.ModelProto`) to be joined into one graph use the same opset."""
    if first.opset_import[0].version != second.opset_import[0].version:
        raise ValueError(f"the two models' opsets differ: {first.opset_import} and {second.opset_import}")


def join(main: Any, veto: Any, loose_x: float, capped: Mapping[str, float] = MappingProxyType({"X": 1.0})) -> Any:
    """The joined `onnx.ModelProto` of two verifier models (`onnx.ModelProto`, the same opset): on a loose row each
    shape in `capped` (shape name: scale) gets the lower of `main`'s probability and `veto`'s times the scale. A
    scale above one lets through what `veto` is only fairly sure of: with scale t / v a row reaches the threshold
    t exactly when `main` reaches t and `veto` reaches v."""
    from onnx import TensorProto, compose, helper  # type: ignore[import-not-found,unused-ignore]

    check_capped(capped)

    check_same_opset(main, veto)
    m = compose.add_prefix(main, MAIN, rename_inputs=False)  # reads `crops` and `claim` itself
    v = compose.add_prefix(veto, VETO)  # reads `veto_crops` and `veto_claim`, the loose rows
    pm, pv = m.graph.output[0].name, v.graph.output[0].name

    def ints(name: str, values: list[int]) -> Any:
        return helper.make_tensor(name, TensorProto.INT64, [len(values)], values)

    consts = [
        helper.make_tensor("j_slot", TensorProto.INT64, [], [LOOSE_SLOT]),
        helper.make_tensor("j_half", TensorProto.FLOAT, [], [0.5]),
        *(ints(f"j_{k}", [k]) for k in range(len(SHAPES) + 2)),
    ]
    node = helper.make_node
    pick = [  # the loose rows' indices, as GatherND wants them: (k, 1)
        node("Gather", ["claim", "j_slot"], ["j_loose_slot"], axis=1),
        node("Greater", ["j_loose_slot", "j_half"], ["j_loose"]),
        node("NonZero", ["j_loose"], ["j_rows_t"]),
        node("Transpose", ["j_rows_t"], ["j_rows"], perm=[1, 0]),
        node("GatherND", ["crops", "j_rows"], ["veto_crops"]),
        node("GatherND", ["claim", "j_rows"], ["veto_claim"]),
    ]
    write = [node("GatherND", [pm, "j_rows"], ["j_main_rows"])]  # the loose rows of both networks
    columns, lost = [], []
    for k, shape in enumerate(SHAPE_NAMES):  # a capped shape: min(main, scale x veto); the others are main's
        write.append(node("Slice", ["j_main_rows", f"j_{k}", f"j_{k + 1}", "j_1"], [f"j_main_{k}"]))
        if shape not in capped:
            columns.append(f"j_main_{k}")
            continue
        write.append(node("Slice", [pv, f"j_{k}", f"j_{k + 1}", "j_1"], [f"j_veto_{k}"]))
        cap = f"j_veto_{k}"
        if capped[shape] != 1.0:
            consts.append(helper.make_tensor(f"j_scale_{k}", TensorProto.FLOAT, [], [capped[shape]]))
            write.append(node("Mul", [cap, f"j_scale_{k}"], [f"j_cap_{k}"]))
            cap = f"j_cap_{k}"
        write += [
            node("Min", [f"j_main_{k}", cap], [f"j_min_{k}"]),
            node("Sub", [f"j_main_{k}", f"j_min_{k}"], [f"j_lost_{k}"]),
        ]
        columns.append(f"j_min_{k}")
        lost.append(f"j_lost_{k}")
    n = len(SHAPES)
    write += [  # 'none' gets what the capped shapes lost, so a row still sums to one
        node("Slice", ["j_main_rows", f"j_{n}", f"j_{n + 1}", "j_1"], ["j_none"]),
        node("Sum", ["j_none", *lost], ["j_none2"]),
        node("Concat", [*columns, "j_none2"], ["j_rows_new"], axis=1),
        node("ScatterND", [pm, "j_rows", "j_rows_new"], ["probabilities"]),
    ]
    out = helper.make_tensor_value_info("probabilities", TensorProto.FLOAT, ["n", len(SHAPES) + 1])
    graph = helper.make_graph(
        pick + list(m.graph.node) + list(v.graph.node) + write,
        JOINED,
        list(main.graph.input),
        [out],
        list(m.graph.initializer) + list(v.graph.initializer) + consts,
    )
    joined = helper.make_model(graph, opset_imports=main.opset_import, producer_name="services.vision.ensemble")
    joined.ir_version = main.ir_version
    for p in main.metadata_props:
        value = p.value
        if p.key == "loose_thresholds":
            value = ",".join([f"{loose_x:g}", *p.value.split(",")[1:]])
        if p.key != CAPPED_KEY:
            joined.metadata_props.add(key=p.key, value=value)
    joined.metadata_props.add(key=CAPPED_KEY, value=capped_text(capped))
    joined.doc_string = f"vision mark verifier: python -m services.vision.ensemble MAIN VETO (loose {capped_text(capped)})"
    return joined


def main(
    main_model: Annotated[
        Path, typer.Argument(help="the network that judges every row (the default recipe; of a joined model: its main)")
    ],
    veto_model: Annotated[
        Path, typer.Argument(help="the network whose X a loose row also needs (--everyday; of a joined model: its veto)")
    ],
    loose_x: Annotated[float, typer.Option(help="the X probability (the lower of the two) a loose row needs")] = 0.1,
    veto_shapes: Annotated[
        str,
        typer.Option(help='the shapes whose probability on a loose row is the lower of the two: "X,TRIANGLE*9" '
                     "(TRIANGLE: the lower of main's and 9 x veto's)"),
    ] = "X",
    out: Annotated[Path, typer.Option(help="where to write the joined model")] = MODEL_PATH,
) -> None:
    import onnx  # type: ignore[import-not-found,unused-ignore]

    for path in (main_model, veto_model):
        Verifier.load(path)  # refuses a file that is not a verifier model for this code's inputs
    try:
        capped = parse_capped(veto_shapes)
        check_capped(capped)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--veto-shapes") from None
    joined = join(network(onnx.load(str(main_model)), MAIN), network(onnx.load(str(veto_model)), VETO), loose_x,
                  capped)
    save_checked(joined, out)


def save_checked(model: Any, out: Path) -> None:
    """Write a joined verifier `model` (`onnx.ModelProto`) to `out` after ONNX's checker, load it back as a `Verifier`
    (which refuses a model not for this code's inputs) and say what was written."""
    import onnx  # type: ignore[import-not-found,unused-ignore]

    onnx.checker.check_model(model)
    onnx.save(model, str(out))
    v = Verifier.load(out)
    typer.echo(f"wrote {out} ({out.stat().st_size} bytes; thresholds {v.thresholds}, loose {v.loose_thresholds})")


if __name__ == "__main__":
    typer.run(main)
