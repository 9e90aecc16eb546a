"""Train the mark proposer (`proposer.onnx`) on frames of the TUNING generator (`--blind`: the blind one's too).

    pip install -e '.[train]'          # PyTorch and onnx: training only, never needed to run the service
    python -m services.vision.proposer_training [--frames 24000] [--epochs 10] [--seed 20261125]
                                                [--jobs 2] [--threads 2] [--cache FILE] [--width N x5]
                                                [--blind SHARE] [--arrows] [--everyday] [--sheen SHARE]
                                                [--keep-float FILE | --from-float FILE]

Its defaults trained the float32 model of 48ea60e (37 min on 2 cores); the committed `proposer.onnx` is
that model quantised by `--from-float` (round vision19), the last step of every training run too.

Frames come from `synthetic.SceneGenerator` (never from `heldout.py`), cycling X, O, TRIANGLE and
mark-free, in chunks of CHUNK frames: even chunks with the verifier training's default variation, odd
ones with its extra clutter (`training.DEFAULT`, `training.CLUTTERED`), and in both a share of the
cards held by people's variety of fingers. Each frame is kept only as the network's input
(`proposer.network_input`: grey, half of 640x480) and its one mark's shape and box. With `--blind SHARE`
(round vision30; not the committed recipe) SHARE frames of `blind.BlindGenerator` per tuning frame are added
in whole chunks after the tuning ones (seeds `training.BLIND_SEEDS` on, as the verifier's `--blind`), for
training only: the held-back tenth the report is made on stays tuning chunks. With `--arrows` and `--everyday`
(round vision43; not the committed recipe) the cluttered chunks also draw the verifier training's extra kinds of
clutter (arrows; stars, check marks and clock faces: `training.more_clutter`), so the proposer learns that they
are not marks; the benches judge such a model with `--set proposer_model=FILE`. With `--sheen SHARE` (round vision66;
not the committed recipe) a share of the cards in every chunk is glossy, with a lamp's reflection over the mark
(`synthetic.Variation.sheen`, as the verifier's `--sheen`).

The network (`_net`) is a small fully convolutional encoder-decoder (stride 32 at its deepest, for the
context of a mark filling the frame; output at stride 8) trained with CenterNet's losses (a focal loss
on Gaussian centre heatmaps; L1 on the size and offset at the centre cell), fixed seed, with flips,
contrast and noise as augmentation, exported to ONNX with its input format in its metadata, then
quantised to static int8 (`quantize`, activation ranges from training frames). The last tenth of the
chunks is held back to report the proposals' recall and stray proposals at each `--threshold`, for the
int8 model and, at the middle threshold, the float one.
"""

from __future__ import annotations

import json
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import numpy as np
import typer

from schemas.messages import Shape
from services.vision.proposer import HEADS, INPUT_FORMAT, MODEL_PATH, SCALE, SHAPES, STRIDE, Proposer, decode
from services.vision.synthetic import Box, SceneGenerator
from services.vision.training import (
    BLIND_SEEDS,
    CLUTTERED,
    DEFAULT,
    ORDER,
    blind_chunks,
    more_clutter,
    split_chunks,
)

if TYPE_CHECKING:
    import torch  # type: ignore[import-not-found,unused-ignore]

CHUNK = 500
HANDS = 0.3  # share of cards with fingers that have people's variety of fingers (`Variation.hand_variety`)
WIDTH, HEIGHT = 640, 480
DOC = "vision mark proposer: python -m services.vision.proposer_training"
CALIBRATION = 25
WIDTHS = (16, 24, 32, 64, 96)
"""the network's channels at strides 2, 4, 8, 16 and 32"""
Chunk = tuple[np.ndarray, np.ndarray]
"""one chunk's network inputs (n, h, w) uint8 and labels (n, 5) (`_arrays`)"""


def _arrays(draw: Callable[[Shape | None], tuple[np.ndarray, list[tuple[Shape, Box]]]], frames: int) -> Chunk:
    """(inputs (n, h, w) uint8 at the network's scale, labels (n, 5) float32: shape index or -1, then the
    mark's box x, y, w, h in frame pixels) for `frames` frames of `draw` (BGR frame and its marks), cycling
    X, O, TRIANGLE and mark-free."""
    import cv2

    from services.vision.detector import to_gray
    from services.vision.proposer import network_input

    cv2.setNumThreads(1)
    inputs = np.zeros((frames, HEIGHT // SCALE, WIDTH // SCALE), np.uint8)
    labels = np.full((frames, 5), -1.0, np.float32)
    for i in range(frames):
        img, truth = draw(ORDER[i % len(ORDER)])
        inputs[i] = np.round(network_input(to_gray(img))[0, 0] * 255.0).astype(np.uint8)
        for shape, box in truth:
            labels[i] = (SHAPES.index(shape), *box)
    return inputs, labels


def render(seed: int, frames: int, arrows: bool = False, everyday: bool = False, sheen: float = 0.0) -> Chunk:
    """`_arrays` of `frames` tuning frames drawn with `seed`; `arrows` and `everyday` add the verifier training's
    extra kinds of clutter to a cluttered (odd-seed) chunk (`training.more_clutter`); a share `sheen` of the cards is
    glossy (`Variation.sheen`)."""
    variation = more_clutter(
        (CLUTTERED if seed % 2 else DEFAULT).only(hand_variety=HANDS, sheen=sheen), seed, arrows, everyday
    )
    gen = SceneGenerator(width=WIDTH, height=HEIGHT, seed=seed, variation=variation)

    def draw(shape: Shape | None) -> tuple[np.ndarray, list[tuple[Shape, Box]]]:
        img, truth = gen.frame(shape)
        return img, [(t.shape, t.box) for t in truth]

    return _arrays(draw, frames)


def render_blind(seed: int, frames: int) -> Chunk:
    """`_arrays` of `frames` frames of the blind generator (`blind.BlindGenerator(seed)`), for `--blind`
    (round vision30): a second way of drawing cards, marks, hands and rooms to learn from."""
    from services.vision.blind import BlindGenerator

    gen = BlindGenerator(seed=seed, width=WIDTH, height=HEIGHT)

    def draw(shape: Shape | None) -> tuple[np.ndarray, list[tuple[Shape, Box]]]:
        img, label = gen.frame(shape)
        return img, [] if label is None else [(label.shape, label.box)]

    return _arrays(draw, frames)


def render_all(
    frames: int, seed: int, jobs: int, cache: Path | None, blind: float = 0.0, arrows: bool = False,
    everyday: bool = False, sheen: float = 0.0,
) -> list[Chunk]:
    """`render` of chunks with seeds seed, seed + 1, ... (with `arrows` and `everyday` clutter, a share `sheen` of glossy
    cards); then, with `blind` > 0, `blind_chunks(frames, blind, CHUNK)` chunks of `render_blind` with seeds seed +
    BLIND_SEEDS, ... (listed after the tuning ones); read from / written to `cache` (one made with other seeds, other
    clutter or another `sheen` is not used)."""
    tuning = [seed + k for k in range((frames + CHUNK - 1) // CHUNK)]
    blinds = [seed + BLIND_SEEDS + k for k in range(blind_chunks(frames, blind, CHUNK))]
    seeds = tuning + blinds
    clutter = [int(arrows), int(everyday)]
    if cache is not None and cache.exists():
        with np.load(cache) as z:
            made_with = z["clutter"].tolist() if "clutter" in z else [0, 0]
            glossy = float(z["sheen"]) if "sheen" in z else 0.0
            if z["seeds"].tolist() == seeds and made_with == clutter and glossy == sheen:
                return [(z[f"x_{k}"], z[f"y_{k}"]) for k in range(len(seeds))]
    n = len(tuning)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        parts = list(pool.map(render, tuning, [CHUNK] * n, [arrows] * n, [everyday] * n, [sheen] * n))
        parts += pool.map(render_blind, blinds, [CHUNK] * len(blinds))
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        arrays = {f"{name}_{k}": a for k, p in enumerate(parts) for name, a in zip("xy", p, strict=True)}
        np.savez(  # type: ignore[arg-type]
            cache, seeds=np.array(seeds), clutter=np.array(clutter), sheen=np.array(sheen), **arrays
        )
    return parts


def targets(labels: np.ndarray, h: int, w: int) -> tuple[np.ndarray, ...]:
    """CenterNet targets for labels (n, 5) at output size h x w: heatmaps (n, 3, h, w), each mark's
    centre cell index (n,) (-1: none), and its log size (n, 2) and offset (n, 2)."""
    n = len(labels)
    heat = np.zeros((n, len(SHAPES), h, w), np.float32)
    index = np.full(n, -1, np.int64)
    size = np.zeros((n, 2), np.float32)
    offset = np.zeros((n, 2), np.float32)
    cell = STRIDE * SCALE
    gy, gx = np.mgrid[0:h, 0:w].astype(np.float32)
    for i, (k, x, y, bw, bh) in enumerate(labels):
        if k < 0:
            continue
        cx, cy = (x + bw / 2) / cell, (y + bh / 2) / cell
        ix, iy = min(w - 1, int(cx)), min(h - 1, int(cy))
        sigma = max(0.7, max(bw, bh) / cell / 6.0)
        g = np.exp(-((gx - ix) ** 2 + (gy - iy) ** 2) / (2 * sigma**2))
        heat[i, int(k)] = np.maximum(heat[i, int(k)], g)
        index[i] = iy * w + ix
        size[i] = (np.log(max(bw, 1.0) / SCALE), np.log(max(bh, 1.0) / SCALE))
        offset[i] = (cx - ix, cy - iy)
    return heat, index, size, offset


def _net(widths: tuple[int, ...] = WIDTHS) -> torch.nn.Module:
    import torch  # type: ignore[import-not-found,unused-ignore]
    import torch.nn.functional as F  # type: ignore[import-not-found,unused-ignore]
    from torch import nn  # type: ignore[import-not-found,unused-ignore]

    def block(a: int, b: int, stride: int = 1, dilation: int = 1) -> nn.Module:
        return nn.Sequential(
            nn.Conv2d(a, b, 3, stride=stride, padding=dilation, dilation=dilation, bias=False),
            nn.BatchNorm2d(b),
            nn.ReLU(),
        )

    class Net(nn.Module):
        """Encoder: strides 2, 4, 8 (the output's), 16 and 32, the deeper stages dilated for reach; decoder:
        each coarser stage upsampled and added to the finer one; heads: 1x1 convolutions."""

        def __init__(self) -> None:
            super().__init__()
            w2, w4, w8, w16, w32 = widths
            self.fine = nn.Sequential(block(1, w2, 2), block(w2, w4, 2), block(w4, w8, 2), block(w8, w8))
            self.mid = nn.Sequential(block(w8, w16, 2), block(w16, w16), block(w16, w16, dilation=2))
            self.deep = nn.Sequential(block(w16, w32, 2), block(w32, w32), block(w32, w32, dilation=2))
            self.lat_deep = nn.Conv2d(w32, w16, 1)
            self.mix_mid = block(w16, w16)
            self.lat_mid = nn.Conv2d(w16, w8, 1)
            self.mix_fine = block(w8, w8)
            self.heads = nn.Conv2d(w8, HEADS, 1)
            assert self.heads.bias is not None
            with torch.no_grad():  # CenterNet's start: every centre unlikely (sigmoid ~0.01)
                self.heads.bias[: len(SHAPES)].fill_(-4.6)

        def forward(self, frame: torch.Tensor) -> torch.Tensor:
            fine = self.fine(frame)
            mid = self.mid(fine)
            deep = self.deep(mid)
            up_mid = self.mix_mid(
                mid + F.interpolate(self.lat_deep(deep), size=mid.shape[-2:], mode="nearest")
            )
            up_fine = self.mix_fine(
                fine + F.interpolate(self.lat_mid(up_mid), size=fine.shape[-2:], mode="nearest")
            )
            out = self.heads(up_fine)
            heat = torch.sigmoid(out[:, : len(SHAPES)])
            return torch.cat([heat, out[:, len(SHAPES) :]], dim=1)

    return Net()


def _augment(x: np.ndarray, labels: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Flips (every shape stays its class) with the boxes mirrored, contrast, brightness and noise. x:
    (n, h, w) float32 in 0..1."""
    x, labels = x.copy(), labels.copy()
    fw, fh = x.shape[2] * SCALE, x.shape[1] * SCALE
    for i in range(len(x)):
        if rng.random() < 0.5:
            x[i] = x[i, :, ::-1]
            labels[i, 1] = fw - labels[i, 1] - labels[i, 3]
        if rng.random() < 0.5:
            x[i] = x[i, ::-1, :]
            labels[i, 2] = fh - labels[i, 2] - labels[i, 4]
    n = len(x)
    gain = rng.uniform(0.7, 1.3, (n, 1, 1)).astype(np.float32)
    bias = rng.uniform(-0.1, 0.1, (n, 1, 1)).astype(np.float32)
    x = (x - 0.5) * gain + 0.5 + bias
    x += rng.uniform(0, 0.03, (n, 1, 1)).astype(np.float32) * rng.standard_normal(x.shape).astype(np.float32)
    return np.clip(x, 0.0, 1.0), labels


def _loss(out: torch.Tensor, heat: Any, index: Any, size: Any, offset: Any) -> torch.Tensor:
    import torch  # type: ignore[import-not-found,unused-ignore]
    import torch.nn.functional as F  # type: ignore[import-not-found,unused-ignore]

    p = out[:, : len(SHAPES)].clamp(1e-4, 1 - 1e-4)
    pos = heat.eq(1.0).float()
    neg = 1.0 - pos
    focal = -(pos * (1 - p) ** 2 * torch.log(p) + neg * (1 - heat) ** 4 * p**2 * torch.log(1 - p)).sum()
    has = index >= 0
    n_pos = max(1, int(has.sum()))
    reg = torch.zeros(())
    if has.any():
        flat = out[has, len(SHAPES) :].flatten(2)  # (m, 4, h*w)
        at = flat.gather(2, index[has].view(-1, 1, 1).expand(-1, 4, 1)).squeeze(2)
        reg = F.l1_loss(at[:, :2], size[has], reduction="sum") * 0.2 + F.l1_loss(
            at[:, 2:], offset[has], reduction="sum"
        )
    return (focal + reg) / n_pos


def fit(
    parts: list[Chunk],
    seed: int,
    epochs: int,
    threads: int,
    log: Any,
    widths: tuple[int, ...] = WIDTHS,
) -> Any:
    """Train `_net` on the rendered chunks; fixed seed."""
    import torch  # type: ignore[import-not-found,unused-ignore]

    torch.manual_seed(seed)
    torch.set_num_threads(threads)
    rng = np.random.default_rng(seed)
    x = np.concatenate([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    net = _net(widths)
    batch = 32
    steps = epochs * ((len(x) + batch - 1) // batch)
    opt = torch.optim.AdamW(net.parameters(), lr=2e-3, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=2e-3, total_steps=steps, pct_start=0.15)
    oh, ow = x.shape[1] // STRIDE, x.shape[2] // STRIDE
    for epoch in range(epochs):
        net.train()
        order = rng.permutation(len(x))
        total, t0 = 0.0, time.monotonic()
        for k in range(0, len(x), batch):
            idx = order[k : k + batch]
            xb, yb = _augment(x[idx].astype(np.float32) / 255.0, y[idx], rng)
            heat, index, size, offset = (torch.from_numpy(a) for a in targets(yb, oh, ow))
            loss = _loss(net(torch.from_numpy(xb[:, None])), heat, index, size, offset)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += loss.item() * len(idx)
        log(f"epoch {epoch + 1}/{epochs}: loss {total / len(x):.4f} ({time.monotonic() - t0:.0f} s)")
    return net.eval()


def export(net: Any, out: Path) -> None:
    """ONNX with input `frame` (1, 1, h, w), output `heads`, any frame size, its input format as metadata."""
    import io

    import onnx  # type: ignore[import-not-found,unused-ignore]
    import torch  # type: ignore[import-not-found,unused-ignore]

    buf = io.BytesIO()
    torch.onnx.export(
        net.eval(),
        (torch.zeros(1, 1, HEIGHT // SCALE, WIDTH // SCALE),),
        buf,
        input_names=["frame"],
        output_names=["heads"],
        dynamic_axes={"frame": {2: "h", 3: "w"}, "heads": {2: "oh", 3: "ow"}},
        opset_version=17,
        dynamo=False,
    )
    model = onnx.load_from_string(buf.getvalue())
    entry = model.metadata_props.add()
    entry.key, entry.value = "input_format", INPUT_FORMAT
    model.doc_string = DOC
    onnx.save(model, str(out))


def calibration_frames(train: list[Chunk]) -> np.ndarray:
    """The frames that set the int8 model's activation ranges: the first CALIBRATION of every third
    training chunk (both variations, every shape and mark-free; with `--blind`, every third blind chunk too)."""
    return np.concatenate([xs[:CALIBRATION] for xs, _ in train[::3]])


def quantize(float_model: Path, out: Path, frames: np.ndarray, work: Path) -> None:
    """`float_model` as static int8 (onnxruntime's QDQ format, per-channel weights, activation ranges
    from `frames` by min-max), its metadata kept. Weights use 7 bits (`reduce_range`): CPUs without
    VNNI multiply u8 x s8 pairs into saturating 16-bit sums, and 7-bit weights never saturate, so the
    model should give the same output on x86 CPUs with and without VNNI (onnxruntime's advice for
    per-channel models; measured only on one with it)."""
    import onnx  # type: ignore[import-not-found,unused-ignore]
    from onnxruntime.quantization import (  # type: ignore[import-untyped,unused-ignore]
        CalibrationDataReader,
        QuantFormat,
        QuantType,
        quant_pre_process,
        quantize_static,
    )

    class Frames(CalibrationDataReader):  # type: ignore[misc]
        def __init__(self) -> None:
            self.left = iter(frames)

        def get_next(self) -> dict[str, np.ndarray] | None:
            x = next(self.left, None)
            return None if x is None else {"frame": (x.astype(np.float32) / 255.0)[None, None]}

    prepared = work / "prepared.onnx"
    quant_pre_process(str(float_model), str(prepared))
    quantize_static(
        str(prepared),
        str(out),
        Frames(),
        quant_format=QuantFormat.QDQ,
        per_channel=True,
        reduce_range=True,
        activation_type=QuantType.QUInt8,
        weight_type=QuantType.QInt8,
    )
    model = onnx.load(str(out))
    meta = {m.key: m.value for m in model.metadata_props}
    if meta.get("input_format") != INPUT_FORMAT:  # the quantiser keeps it today; never ship a model without
        raise RuntimeError(f"{out}: the quantised model lost its input format ({meta})")
    entry = model.metadata_props.add()
    entry.key, entry.value = "weights", "int8"
    model.doc_string = DOC + " (static int8)"
    onnx.save(model, str(out))


def report(proposer: Proposer, val: list[Chunk], threshold: float) -> dict[str, Any]:
    """On the held-back chunks, with peaks of at least `threshold`: the share of marks with a proposal of
    the right shape whose centre lies in the mark's box, and proposals per frame elsewhere."""
    found = np.zeros(len(SHAPES), int)
    marks = np.zeros(len(SHAPES), int)
    stray = 0
    frames = 0
    for xs, ys in val:
        for img, lab in zip(xs, ys, strict=True):
            frames += 1
            props = decode(
                proposer.session.run(None, {"frame": (img.astype(np.float32) / 255.0)[None, None]})[0][0],
                threshold,
            )
            k = int(lab[0])
            hit = False
            for p in props:
                cx, cy = p.box[0] + p.box[2] / 2, p.box[1] + p.box[3] / 2
                inside = k >= 0 and lab[1] <= cx <= lab[1] + lab[3] and lab[2] <= cy <= lab[2] + lab[4]
                if inside and p.shape is SHAPES[k] and not hit:
                    hit = True
                elif not inside:
                    stray += 1
            if k >= 0:
                marks[k] += 1
                found[k] += hit
    return {
        "held_back_frames": frames,
        "recall": {
            s.value: round(float(f / max(1, m)), 4) for s, f, m in zip(SHAPES, found, marks, strict=True)
        },
        "stray_proposals_per_frame": round(stray / max(1, frames), 4),
    }


def main(
    frames: Annotated[int, typer.Option(help="tuning frames to render")] = 24000,
    seed: Annotated[int, typer.Option(help="base seed (generator chunks and the network)")] = 20261125,
    jobs: Annotated[int, typer.Option(help="rendering processes")] = 2,
    threads: Annotated[int, typer.Option(help="PyTorch threads for training")] = 2,
    epochs: Annotated[int, typer.Option(help="training epochs")] = 10,
    cache: Annotated[Path | None, typer.Option(help="keep the rendered frames here (never commit)")] = None,
    out: Annotated[Path, typer.Option(help="where to write the model")] = MODEL_PATH,
    thresholds: Annotated[
        list[float], typer.Option("--threshold", help="heatmap peaks to report the held-back frames at")
    ] = [0.2, 0.3, 0.5],  # noqa: B006 - typer reads the default
    widths: Annotated[
        list[int], typer.Option("--width", help="channels at strides 2, 4, 8, 16, 32 (five times)")
    ] = list(WIDTHS),  # noqa: B006 - typer reads the default
    keep_float: Annotated[Path | None, typer.Option(help="also keep the trained float32 model here")] = None,
    from_float: Annotated[
        Path | None,
        typer.Option(help="skip training: quantise this float32 model (the frames still calibrate)"),
    ] = None,
    blind: Annotated[
        float,
        typer.Option(
            help="also learn from the blind generator (blind.py): this many of its frames per tuning frame, for "
            "training only (round vision30; the bench's blind split then no longer judges the proposer blind)"
        ),
    ] = 0.0,
    arrows: Annotated[
        bool,
        typer.Option(help="the cluttered chunks also draw arrows, as the verifier's --arrows (round vision43)"),
    ] = False,
    everyday: Annotated[
        bool,
        typer.Option(
            help="the cluttered chunks also draw stars, check marks and clock faces, as the verifier's --everyday "
            "(round vision43)"
        ),
    ] = False,
    sheen: Annotated[
        float,
        typer.Option(
            min=0.0,
            max=1.0,
            help="share of cards that are glossy, a lamp's reflection over the mark, as the verifier's --sheen (round "
            "vision66)",
        ),
    ] = 0.0,
) -> None:
    if len(widths) != 5:
        raise typer.BadParameter("give --width five times: strides 2, 4, 8, 16 and 32", param_hint="--width")
    if blind < 0:
        raise typer.BadParameter(f"--blind {blind}: a share of at least 0", param_hint="--blind")
    t0 = time.monotonic()
    parts = render_all(frames, seed, jobs, cache, blind, arrows, everyday, sheen)
    train, val = split_chunks(parts, blind_chunks(frames, blind, CHUNK))
    typer.echo(f"rendered {sum(len(p[0]) for p in parts)} frames in {time.monotonic() - t0:.0f} s", err=True)
    with tempfile.TemporaryDirectory() as tmp:
        if from_float is None:
            from_float = keep_float or Path(tmp) / "float.onnx"
            net = fit(
                train, seed, epochs, threads, log=lambda m: typer.echo(m, err=True), widths=tuple(widths)
            )
            export(net, from_float)
        quantize(from_float, out, calibration_frames(train), Path(tmp))
        result: dict[str, Any] = {"train_frames": sum(len(p[0]) for p in train), "arrows": arrows, "everyday": everyday,
                                  "blind": blind, "sheen": sheen, "seed": seed}
        for t in thresholds:
            result[f"at_{t:g}"] = report(Proposer.load(out), val, t)
        middle = thresholds[len(thresholds) // 2]
        result[f"float_at_{middle:g}"] = report(Proposer.load(from_float), val, middle)
    result["model_bytes"] = out.stat().st_size
    result["seconds"] = round(time.monotonic() - t0)
    typer.echo(json.dumps(result, indent=2))


if __name__ == "__main__":
    typer.run(main)
