"""Round vision22e: one ONNX verifier whose output is the average of two verifiers' softmax outputs.

    .venv/bin/python docs/experiments/scripts/vision22e_average.py FIRST.onnx SECOND.onnx OUT.onnx

Both models must take the same inputs (`crops`, `claim`) and give `probabilities`; OUT has the same inputs, output
and the FIRST model's metadata (thresholds, input format), so `services/vision/verifier.py` runs it unchanged."""
import sys

import onnx
from onnx import helper

SHARED = {"crops", "claim"}


def prefixed(model: onnx.ModelProto, p: str) -> onnx.GraphProto:
    g = onnx.GraphProto()
    g.CopyFrom(model.graph)
    name = lambda n: n if n in SHARED or n == "" else p + n  # noqa: E731
    for node in g.node:
        node.name = p + node.name
        node.input[:] = [name(n) for n in node.input]
        node.output[:] = [name(n) for n in node.output]
    for init in g.initializer:
        init.name = p + init.name
    for vi in g.value_info:
        vi.name = p + vi.name
    return g


out = sys.argv[3]
a, b = onnx.load(sys.argv[1]), onnx.load(sys.argv[2])
ga, gb = prefixed(a, "a_"), prefixed(b, "b_")
mean = helper.make_node("Mean", ["a_probabilities", "b_probabilities"], ["probabilities"], name="average")
graph = helper.make_graph(
    list(ga.node) + list(gb.node) + [mean], "averaged_verifier", list(a.graph.input), list(a.graph.output),
    list(ga.initializer) + list(gb.initializer), value_info=list(ga.value_info) + list(gb.value_info),
)
model = helper.make_model(graph, opset_imports=list(a.opset_import), producer_name="vision22e_average")
model.ir_version = a.ir_version
for prop in a.metadata_props:
    model.metadata_props.add(key=prop.key, value=prop.value)
onnx.checker.check_model(model)
onnx.save(model, out)
print(f"{out}: {len(model.graph.node)} nodes")
