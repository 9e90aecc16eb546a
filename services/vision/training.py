"""Train the mark verifier (`verifier.onnx`) on candidates from the TUNING generator (`--blind`: the blind one's too).

The committed `verifier.onnx` is two networks this command makes, the default recipe and `--everyday --crossings 6
--proposals 0.3` (round vision45c; `--everyday` alone from round vision23g), joined by `python -m
services.vision.ensemble` (see there), and since round vision68b raised by a third, the first fine-tuned with `--init
--sheen` (`danger_raise.py`, see there). The committed `verifier_triangles.onnx`,
asked only about claimed triangles the first refuses (`DetectorConfig.hand_triangle`, round vision34), is `--hand-drawn
0.4 --hand-drawn-shapes TRIANGLE` (never written by default: `--out` names the file).

    pip install -e '.[train]'          # PyTorch and onnx: training only, never needed to run the service
    python -m services.vision.training --out FILE [--frames 16000] [--seed 20261123] [--jobs 2] [--cache FILE]
                                       [--proposals PEAK] [--printed SHARE] [--hands SHARE]
                                       [--levels PYRAMID] [--arrows] [--hand-drawn SHARE [--hand-drawn-shapes S]]
                                       [--everyday] [--crossings N] [--blind SHARE]
                                       [--sheen SHARE [--sheen-shapes S]] [--epochs 6] [--width 1]
                                       [--init MODEL] [--lr 3e-3]
                                       (recipe variants, off by default)

Frames come from `synthetic.SceneGenerator` (never from `heldout.py`; for `--blind`, below, also from
`blind.py`), cycling X, O, TRIANGLE and mark-free, half of them with the default variation and half with
extra clutter (8-14 distractors: more words, signs and textures to learn 'not a mark' from). Every
component that passes the detector's shape tests is a candidate (`MarkDetector.candidates`, verifier
off), and so is every loose one (no shape found, but ink on a light plain surround:
`MarkDetector._loose`), with no claimed shape; with
`--proposals PEAK` (round vision18b; not the committed recipe) so is every proposal of the committed
proposer (`proposer.py`), cropped as the detector crops it. Each candidate's label is the true mark's
class when its box overlaps the true box with IoU >= 0.4, else 'none'. Each candidate is its three
crops (`verifier.crops`) and its claim (`verifier.claim`). With `--blind SHARE` (rounds vision29-29b; not
the committed recipe) the network also learns from `blind.BlindGenerator`'s frames, SHARE of them per
tuning frame in whole chunks listed after the tuning ones (`harvest_blind`; training only: the held-back
tenth the report is made on stays tuning chunks). The blind split of `bench/vision_bench.py` then no
longer judges that network blind: other seeds, but the generator's look.

The model (`Net`) is a small convolutional network trained with PyTorch (fixed seed, one thread, the
eight flips and quarter turns of the crops plus contrast, blur and noise as augmentation), exported to
ONNX with the thresholds in its metadata; the service runs it with onnxruntime. The last tenth of the
frames is kept out of training to report the verifier's effect on the candidates the detector keeps.
"""

from __future__ import annotations

import itertools
import json
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import numpy as np
import typer

from schemas.messages import Shape
from services.vision.detector import Candidate, DetectorConfig, MarkDetector, parse_levels, to_gray
from services.vision.printed import print_words, typefaces
from services.vision.proposer import Proposer
from services.vision.synthetic import DISTRACTORS, SceneGenerator, Variation
from services.vision.verifier import CLASSES, INPUT_FORMAT, N_CLAIM, PATCH, SHAPES, Verifier

if TYPE_CHECKING:
    import torch  # type: ignore[import-not-found,unused-ignore]

ORDER: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
# training leans on the hard cases (the tuning generator's defaults in brackets): filled triangles are
# 40 % of triangle marks (25 %; on a card they are marks, on a wall clutter, and only the context
# tells them apart); 60 % of cards have fingers (40 %), half of them over the mark's edge (30 %)
DEFAULT = Variation(filled_triangle=0.4, fingers=0.6, finger_over=0.5)
# the cluttered chunks draw the tuning generator's main sources of false marks three times as often:
# filled triangles off cards (half on plain light walls), text (letters O and X in words) and decoy
# cards. Their marks also reach past the generator's defaults: cards with borders up to 1.5 x the
# mark's width (3-60 % elsewhere: a small mark on a large sheet is a mark too) and strokes up to a
# quarter of the mark's width (11-19 % elsewhere; an X's bars up to about a fifth of their length, as
# a marker pen draws a small X) - the first CNN, trained without them, refused a small thick X
HARD = ("filled_triangle", "text", "card")
CLUTTERED = DEFAULT.only(
    distractors=(8, 14), kinds=DISTRACTORS + HARD + HARD, border=(0.03, 1.5), stroke=(0.11, 0.25)
)
IOU = 0.4
CHUNK = 250
PRINTED_STREAM = 7  # the printed words' random stream, apart from the generator's (same chunk seed)
# the harvest's detector: geometric tests only, with the service's loose gate (35 grey levels, spread
# 0.7) and pyramid (full, half and quarter resolution), so that the network learns from the candidates
# it is shown in service - pinned, so that the command keeps reproducing the committed model when the
# service's defaults move on
HARVEST = DetectorConfig(
    verify=False, loose_contrast=35.0, loose_texture=0.7, levels=((1, 31), (2, 31, 50), (4, 31))
)


HAND_DRAWN_SHAPES = "X,O,TRIANGLE"


def parse_shapes(text: str) -> tuple[Shape, ...]:
    """"X,TRIANGLE" -> (Shape.X, Shape.TRIANGLE); ValueError naming an unknown shape."""
    names = [t.strip().upper() for t in text.split(",") if t.strip()]
    unknown = [n for n in names if n not in Shape.__members__]
    if unknown or not names:
        raise ValueError(f"shapes {text!r}: comma-separated names of {', '.join(Shape.__members__)}")
    return tuple(Shape[n] for n in names)


def iou(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> float:
    ix = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


Row = tuple[np.ndarray, int, int, bool]  # one candidate: crops, claim index, class index, kept by the detector


def _harvest_detector(levels: str) -> MarkDetector:
    """`HARVEST`'s detector, or one with the pyramid `levels` ("": `HARVEST`'s own)."""
    return MarkDetector(replace(HARVEST, levels=parse_levels(levels)) if levels else HARVEST)


def more_clutter(
    variation: Variation, seed: int, arrows: bool, everyday: bool, crossings: int = 0
) -> Variation:
    """`variation` with, for a cluttered chunk (odd `seed`), arrows drawn as often as each hard kind of clutter
    (`arrows`; round vision21), stars twice, check marks and clock faces once each (`everyday`) and crossing strokes
    `crossings` times (round vision45: 2; vision45c: 6), all from `synthetic.EXTRA_DISTRACTORS`; an even seed's `variation`
    unchanged."""
    if seed % 2 == 0:
        return variation
    extra = ["arrow"] * 3 * arrows + ["star", "star", "check", "clock"] * everyday + ["crossing"] * crossings
    return variation.only(kinds=(*variation.kinds, *extra)) if extra else variation


def harvest(
    seed: int, frames: int, printed: float = 0.0, hands: float = 0.0, levels: str = "", proposals: float = 0.0,
    arrows: bool = False, hand_drawn: float = 0.0, hand_drawn_shapes: str = HAND_DRAWN_SHAPES, everyday: bool = False,
    crossings: int = 0, sheen: float = 0.0, sheen_shapes: str = HAND_DRAWN_SHAPES,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(crops (n, 3, PATCH, PATCH) uint8, claim index (0-2: the shape claimed, 3: loose), class index
    into CLASSES, kept by the detector) for every candidate in `frames` tuning frames drawn with `seed`
    (even seeds: default variation; odd: cluttered), a share `printed` of them with printed words
    (`printed.print_words`) on the scene's background, clear of the mark, before the card is drawn
    over it and the camera's light, blur, noise and JPEG act on all of it; a share `hands` of the cards
    with fingers have people's variety of fingers (`Variation.hand_variety`); `levels` is the pyramid
    the candidates come from ("1:31,2:31,4:31,6:31", `detector.parse_levels`; "": `HARVEST`'s); with
    `proposals` > 0, every proposal of the committed proposer (`proposer.py`) with a peak of at least
    that is a loose candidate too, cropped as the detector crops it (`MarkDetector.proposal_crops`); with
    `arrows`, the cluttered chunks also draw arrows (`synthetic.EXTRA_DISTRACTORS`) as often as each hard kind;
    a share `hand_drawn` of the marks of the shapes in `hand_drawn_shapes` ("X,O,TRIANGLE") is drawn by hand with a
    pen (`Variation.hand_drawn`); with `everyday`, the cluttered chunks' kinds of clutter also list stars twice and check
    marks and clock faces once each, with `crossings` crossing strokes that many times (`synthetic.EXTRA_DISTRACTORS`);
    a share `sheen` of the cards of the marks in `sheen_shapes` is glossy, with a lamp's reflection over the mark
    (`Variation.sheen`, round vision66; `sheen_shapes`, round vision67)."""
    import cv2

    cv2.setNumThreads(1)
    variation = more_clutter(
        (CLUTTERED if seed % 2 else DEFAULT).only(
            hand_variety=hands, hand_drawn=hand_drawn, hand_drawn_shapes=parse_shapes(hand_drawn_shapes), sheen=sheen,
            sheen_shapes=parse_shapes(sheen_shapes),
        ),
        seed, arrows, everyday, crossings,
    )
    gen = SceneGenerator(seed=seed, variation=variation)
    det = _harvest_detector(levels)
    proposer = Proposer.load() if proposals > 0 else None
    words_rng = np.random.default_rng([seed, PRINTED_STREAM])
    faces = typefaces() if printed > 0 else []
    rows: list[Row] = []
    for i in range(frames):
        scene = gen.scene(ORDER[i % len(ORDER)])
        if printed > 0 and words_rng.random() < printed:
            (cx, cy), half = scene.center, scene.size / 2
            mark = (int(cx - half), int(cy - half), int(scene.size), int(scene.size))
            scene.background = print_words(scene.background, words_rng, faces, avoid=[mark], blur=False)
        img, truth = gen.render(scene)
        found = det.candidates(img)
        if proposer is not None:
            gray = to_gray(img)
            found += [
                Candidate(None, p.box, det.proposal_crops(gray, p.box)) for p in proposer.propose(gray, proposals)
            ]
        rows += _labelled(found, [(t.shape, t.box) for t in truth])
    return _stack(rows)


def _labelled(found: list[Candidate], truth: list[tuple[Shape, tuple[int, int, int, int]]]) -> list[Row]:
    """Each candidate with its class: the true mark's whose box it overlaps with IoU >= IOU, else 'none'."""
    rows: list[Row] = []
    for c in found:
        label: Shape | None = None
        for shape, box in truth:
            if iou(c.box, box) >= IOU:
                label = shape
        rows.append((c.crops, len(SHAPES) if c.shape is None else SHAPES.index(c.shape), CLASSES.index(label), c.kept))
    return rows


def _stack(rows: list[Row]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return (
        np.array([r[0] for r in rows], np.uint8).reshape(len(rows), 3, PATCH, PATCH),
        np.array([r[1] for r in rows], np.int64),
        np.array([r[2] for r in rows], np.int64),
        np.array([r[3] for r in rows], bool),
    )


def harvest_blind(seed: int, frames: int, levels: str = "") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`harvest`'s arrays for `frames` frames of the blind generator (`blind.BlindGenerator(seed)`, cycling X, O,
    TRIANGLE and mark-free), for `--blind` (round vision29): a second way of drawing marks, cards, hands and clutter
    to learn from, so that the network is not fitted to one generator's look. The generator's seeds for training
    (`BLIND_SEEDS` on) are far from the small seeds the bench's blind split is run with."""
    import cv2

    from services.vision.blind import BlindGenerator

    cv2.setNumThreads(1)
    gen = BlindGenerator(seed=seed)
    det = _harvest_detector(levels)
    rows: list[Row] = []
    for i in range(frames):
        img, label = gen.frame(ORDER[i % len(ORDER)])
        rows += _labelled(det.candidates(img), [] if label is None else [(label.shape, label.box)])
    return _stack(rows)


# the blind generator's training seeds start here, added to the base seed: far from the small seeds (1, 2, 101 ...)
# that `bench/vision_bench.py --split blind` is run with
BLIND_SEEDS = 1_000_000


def blind_chunks(frames: int, blind: float, chunk: int = CHUNK) -> int:
    """How many `chunk`-frame chunks of the blind generator `--blind` adds to `frames` tuning frames."""
    return round(frames * blind / chunk)


Part = TypeVar("Part")


def split_chunks(parts: list[Part], n_blind: int) -> tuple[list[Part], list[Part]]:
    """(training chunks, held-back chunks) of chunks whose last `n_blind` are the blind generator's (`--blind`, here
    and in `proposer_training`): the held-back tenth, which the report is made on, is the tuning chunks' last; every
    blind chunk is for training."""
    tuning, blinds = parts[: len(parts) - n_blind], parts[len(parts) - n_blind :]
    n_val = max(1, len(tuning) // 10)
    return tuning[:-n_val] + blinds, tuning[-n_val:]


def claimed_kept(part: tuple[np.ndarray, ...], shapes: tuple[Shape, ...]) -> tuple[np.ndarray, ...]:
    """The rows of a harvested chunk whose candidate the shape tests claimed as one of `shapes` and the detector's
    tests kept: what a network asked only about such candidates is shown (`--claimed-kept`; round vision40)."""
    rows = np.isin(part[1], [SHAPES.index(s) for s in shapes]) & part[3]
    return tuple(a[rows] for a in part)


def _same_shapes(cache: Any, key: str, asked: str) -> bool:
    """Whether the shapes a cache (an open `np.load`) was harvested with under `key` are `asked` (any order or case;
    a cache made before the option had all three)."""
    made = str(cache[key]) if key in cache else HAND_DRAWN_SHAPES
    return set(parse_shapes(made)) == set(parse_shapes(asked))


def harvest_all(
    frames: int,
    seed: int,
    jobs: int,
    cache: Path | None,
    printed: float = 0.0,
    hands: float = 0.0,
    levels: str = "",
    proposals: float = 0.0,
    arrows: bool = False,
    hand_drawn: float = 0.0,
    hand_drawn_shapes: str = HAND_DRAWN_SHAPES,
    everyday: bool = False,
    blind: float = 0.0,
    crossings: int = 0,
    sheen: float = 0.0,
    sheen_shapes: str = HAND_DRAWN_SHAPES,
) -> list[tuple[np.ndarray, ...]]:
    """`harvest` of chunks of CHUNK frames with seeds seed, seed + 1, ...; then, with `blind` > 0,
    `blind_chunks(frames, blind)` chunks of `harvest_blind` with seeds seed + BLIND_SEEDS, ... (listed after the
    tuning chunks); read from / written to `cache` (a cache made with other seeds, another `printed`, `hands`,
    `proposals`, `arrows`, `hand_drawn`, `everyday`, `crossings`, `sheen` or `blind` setting, other `hand_drawn_shapes`
    or `sheen_shapes` or another pyramid is not used)."""
    seeds = [seed + k for k in range((frames + CHUNK - 1) // CHUNK)]
    n_blind = blind_chunks(frames, blind)
    if cache is not None and cache.exists():
        with np.load(cache) as z:
            shares = {
                k: float(z[k]) if k in z else 0.0
                for k in ("printed", "hands", "proposals", "arrows", "hand_drawn", "everyday", "blind", "crossings",
                          "sheen")
            }
            pyramid = str(z["levels"]) if "levels" in z else ""
            asked = {"printed": printed, "hands": hands, "proposals": proposals, "arrows": float(arrows),
                     "hand_drawn": hand_drawn, "everyday": float(everyday), "blind": blind,
                     "crossings": float(crossings), "sheen": sheen}
            same = (shares == asked and pyramid == levels
                    and (_same_shapes(z, "hand_drawn_shapes", hand_drawn_shapes) or not hand_drawn)
                    and (_same_shapes(z, "sheen_shapes", sheen_shapes) or not sheen))
            if z["seeds"].tolist() == seeds and same:
                return [tuple(z[f"{k}_{j}"] for j in range(4)) for k in range(len(seeds) + n_blind)]
    n = len(seeds)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        parts: list[tuple[np.ndarray, ...]] = list(
            pool.map(harvest, seeds, [CHUNK] * n, [printed] * n, [hands] * n, [levels] * n, [proposals] * n,
                     [arrows] * n, [hand_drawn] * n, [hand_drawn_shapes] * n, [everyday] * n, [crossings] * n,
                     [sheen] * n, [sheen_shapes] * n)
        )
        parts += pool.map(harvest_blind, [seed + BLIND_SEEDS + k for k in range(n_blind)], [CHUNK] * n_blind,
                          [levels] * n_blind)
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        arrays = {f"{k}_{j}": a for k, p in enumerate(parts) for j, a in enumerate(p)}
        np.savez(  # type: ignore[arg-type]
            cache,
            seeds=np.array(seeds),
            printed=np.array(printed),
            hands=np.array(hands),
            levels=np.array(levels),
            proposals=np.array(proposals),
            arrows=np.array(float(arrows)),
            hand_drawn=np.array(hand_drawn),
            hand_drawn_shapes=np.array(hand_drawn_shapes),
            everyday=np.array(float(everyday)),
            blind=np.array(blind),
            crossings=np.array(float(crossings)),
            sheen=np.array(sheen),
            sheen_shapes=np.array(sheen_shapes),
            **arrays,
        )
    return parts


def _net(width: float = 1.0) -> torch.nn.Module:
    import torch  # type: ignore[import-not-found,unused-ignore]
    from torch import nn  # type: ignore[import-not-found,unused-ignore]

    class Net(nn.Module):
        """Three 3x3 conv + batch-norm + ReLU + 2x2 max-pool stages (32 -> 4 px), then a hidden layer
        that also sees the claim, then the four classes (softmax in the exported graph). `width` scales
        every stage's channels and the hidden layer (1: 16, 32, 48 and 64, the committed recipe's)."""

        def __init__(self) -> None:
            super().__init__()
            chans = (3, *(round(k * width) for k in (16, 32, 48)))
            hidden = round(64 * width)
            layers: list[nn.Module] = []
            for a, b in itertools.pairwise(chans):
                layers += [
                    nn.Conv2d(a, b, 3, padding=1, bias=False),
                    nn.BatchNorm2d(b),
                    nn.ReLU(),
                    nn.MaxPool2d(2),
                ]
            self.features = nn.Sequential(*layers)
            self.hidden = nn.Linear(chans[-1] * (PATCH // 8) ** 2 + N_CLAIM, hidden)
            self.out = nn.Linear(hidden, len(CLASSES))
            self.drop = nn.Dropout(0.3)

        def forward(self, crops: torch.Tensor, claim: torch.Tensor) -> torch.Tensor:
            a = self.features(crops).flatten(1)
            a = torch.relu(self.hidden(torch.cat([a, claim], dim=1)))
            return self.out(self.drop(a))

    return Net()


def _augment(x: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """The same random flip/quarter turn for the three crops of a candidate (a mark stays its class
    under them), a random contrast and brightness change, a slight blur and noise. x: (n, 3, P, P) in
    [0, 1]."""
    import torch  # type: ignore[import-not-found,unused-ignore]
    import torch.nn.functional as F  # type: ignore[import-not-found,unused-ignore]

    n = x.shape[0]
    k = torch.randint(0, 4, (1,), generator=gen).item()
    x = torch.rot90(x, int(k), dims=(2, 3))
    if torch.rand(1, generator=gen).item() < 0.5:
        x = torch.flip(x, dims=(3,))
    gain = 0.6 + 0.6 * torch.rand(n, 1, 1, 1, generator=gen)
    bias = 0.2 * (torch.rand(n, 1, 1, 1, generator=gen) - 0.5)
    x = (x - 0.5) * gain + 0.5 + bias
    blur = torch.rand(n, generator=gen) < 0.3
    if blur.any():
        kern = torch.tensor([0.25, 0.5, 0.25])
        kern2 = (kern[:, None] * kern[None, :]).expand(3, 1, 3, 3)
        x[blur] = F.conv2d(F.pad(x[blur], (1, 1, 1, 1), mode="replicate"), kern2, groups=3)
    x = x + 0.03 * torch.rand(n, 1, 1, 1, generator=gen) * torch.randn(x.shape, generator=gen)
    return x.clamp(0.0, 1.0)


def load_net(net: torch.nn.Module, model: Path) -> None:
    """Set `net` (a `_net` of the same width) to the network of a verifier model file (a joined model's `main`,
    `ensemble.part`), so that it computes what the file computes. The exported graph has each batch norm folded into
    its convolution (weights and a bias), so the convolution takes the folded weights and its batch norm becomes
    the identity plus that bias (mean 0, variance 1 - eps, scale 1). ValueError if the file's network is not
    `net`'s shape."""
    import onnx  # type: ignore[import-not-found,unused-ignore]
    import torch  # type: ignore[import-not-found,unused-ignore]
    from onnx import numpy_helper  # type: ignore[import-not-found,unused-ignore]
    from torch import nn  # type: ignore[import-not-found,unused-ignore]

    from services.vision.ensemble import MAIN, network

    graph = network(onnx.load(str(model)), MAIN).graph
    values = {i.name: numpy_helper.to_array(i) for i in graph.initializer}
    convs = [n for n in graph.node if n.op_type == "Conv"]
    gemms = [n for n in graph.node if n.op_type == "Gemm"]
    layers = [m for m in net.features if isinstance(m, nn.Conv2d | nn.BatchNorm2d)]
    if len(convs) * 2 != len(layers) or len(gemms) != 2:
        raise ValueError(f"{model}: {len(convs)} convolutions and {len(gemms)} dense layers, not this network's")
    pairs = [(conv, layers[2 * k], layers[2 * k + 1]) for k, conv in enumerate(convs)]
    pairs_dense = zip(gemms, (net.hidden, net.out), strict=True)
    with torch.no_grad():
        for node, conv, norm in pairs:
            weight, bias = (torch.from_numpy(values[name].copy()) for name in node.input[1:3])
            if weight.shape != conv.weight.shape:
                raise ValueError(f"{model}: a convolution of {tuple(weight.shape)}, not {tuple(conv.weight.shape)}")
            conv.weight.copy_(weight)
            norm.weight.fill_(1.0)
            norm.bias.copy_(bias)
            norm.running_mean.zero_()
            norm.running_var.fill_(1.0 - norm.eps)
        for node, dense in pairs_dense:
            weight, bias = (torch.from_numpy(values[name].copy()) for name in node.input[1:3])
            if weight.shape != dense.weight.shape:  # torch's Linear is exported as Gemm with transB = 1
                raise ValueError(f"{model}: a dense layer of {tuple(weight.shape)}, not {tuple(dense.weight.shape)}")
            dense.weight.copy_(weight)
            dense.bias.copy_(bias)


def fit(
    x: np.ndarray, c: np.ndarray, y: np.ndarray, seed: int, epochs: int, log: Any = None, width: float = 1.0,
    init: Path | None = None, lr: float = 3e-3,
) -> torch.nn.Module:
    """Train `_net(width)` on crops x (uint8), claim indices c and labels y; fixed seed, one thread; one-cycle learning
    rate up to `lr`. With `init` (a verifier model file, round vision67) the network starts as that file's (`load_net`)
    and its batch norms stay as they are (their statistics frozen, their bias still learnt): it is fine-tuned."""
    import torch  # type: ignore[import-not-found,unused-ignore]
    import torch.nn.functional as F  # type: ignore[import-not-found,unused-ignore]
    from torch import nn  # type: ignore[import-not-found,unused-ignore]

    torch.manual_seed(seed)
    torch.set_num_threads(1)
    gen = torch.Generator().manual_seed(seed)
    net = _net(width)
    if init is not None:
        load_net(net, init)
    xs = torch.from_numpy(x)
    cs = F.one_hot(torch.from_numpy(c), N_CLAIM).float()
    ys = torch.from_numpy(y)
    opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-3)
    batch = 256
    steps = epochs * ((len(ys) + batch - 1) // batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=lr, total_steps=steps) if steps else None
    for epoch in range(epochs):
        net.train()
        if init is not None:
            for m in net.modules():
                if isinstance(m, nn.BatchNorm2d):
                    m.eval()
        order = torch.randperm(len(ys), generator=gen)
        total = 0.0
        for k in range(0, len(ys), batch):
            idx = order[k : k + batch]
            xb = _augment(xs[idx].float() / 255.0, gen)
            loss = F.cross_entropy(net(xb, cs[idx]), ys[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            if sched is not None:
                sched.step()
            total += loss.item() * len(idx)
        if log is not None:
            log(f"epoch {epoch + 1}/{epochs}: loss {total / len(ys):.4f}")
    return net.eval()


def export(net: torch.nn.Module, out: Path, thresholds: tuple[float, ...], loose: tuple[float, ...]) -> None:
    """ONNX with a softmax output `probabilities`, a dynamic batch, and the thresholds as metadata."""
    import io

    import onnx  # type: ignore[import-not-found,unused-ignore]
    import torch  # type: ignore[import-not-found,unused-ignore]

    class WithSoftmax(torch.nn.Module):
        def __init__(self, inner: torch.nn.Module) -> None:
            super().__init__()
            self.inner = inner

        def forward(self, crops: torch.Tensor, claim: torch.Tensor) -> torch.Tensor:
            return torch.softmax(self.inner(crops, claim), dim=1)

    buf = io.BytesIO()
    torch.onnx.export(
        WithSoftmax(net).eval(),
        (torch.zeros(2, 3, PATCH, PATCH), torch.zeros(2, N_CLAIM)),
        buf,
        input_names=["crops", "claim"],
        output_names=["probabilities"],
        dynamic_axes={"crops": {0: "n"}, "claim": {0: "n"}, "probabilities": {0: "n"}},
        opset_version=17,
        dynamo=False,
    )
    model = onnx.load_from_string(buf.getvalue())
    meta = {
        "input_format": INPUT_FORMAT,
        "thresholds": ",".join(f"{t:g}" for t in thresholds),
        "loose_thresholds": ",".join(f"{t:g}" for t in loose),
    }
    for k, v in meta.items():
        entry = model.metadata_props.add()
        entry.key, entry.value = k, v
    model.doc_string = "vision mark verifier: python -m services.vision.training"
    onnx.save(model, str(out))


def report(verifier: Verifier, val: list[tuple[np.ndarray, ...]], out: Path) -> dict[str, Any]:
    """The verifier's effect on the held-back chunks' candidates."""
    xv = np.concatenate([p[0] for p in val])
    cv = np.concatenate([p[1] for p in val])
    yv = np.concatenate([p[2] for p in val])
    kv = np.concatenate([p[3] for p in val])
    prob = np.concatenate(
        [
            verifier.probabilities(xv[k : k + 512], np.eye(N_CLAIM, dtype=np.float32)[cv[k : k + 512]])
            for k in range(0, len(yv), 512)
        ]
    )
    claimed = cv.copy()
    loose = claimed == len(SHAPES)
    claimed[loose] = np.argmax(prob[loose, : len(SHAPES)], axis=1)  # the verifier names a loose one's shape
    need = np.where(
        loose, np.array(verifier.loose_thresholds)[claimed], np.array(verifier.thresholds)[claimed]
    )
    accept = prob[np.arange(len(yv)), claimed] >= need
    true_pos = kv & (yv == claimed)
    false_pos = kv & (yv != claimed)
    loose_true = loose & (yv < len(SHAPES))
    return {
        "held_back_candidates": len(yv),
        "argmax_accuracy": round(float(np.mean(np.argmax(prob, axis=1) == yv)), 4),
        "detector_true_kept": int(true_pos.sum()),
        "detector_true_kept_after_verifier": int((true_pos & accept).sum()),
        "detector_false_kept": int(false_pos.sum()),
        "detector_false_kept_after_verifier": int((false_pos & accept).sum()),
        "loose_candidates": int(loose.sum()),
        "loose_true_marks": int(loose_true.sum()),
        "loose_true_named_right": int((loose_true & (yv == claimed) & accept).sum()),
        "loose_false_named": int((loose & (yv != claimed) & accept).sum()),
        "model_bytes": out.stat().st_size,
    }


def main(
    out: Annotated[
        Path,
        typer.Option(
            help="where to write the model; never the committed verifier.onnx by default: that file is two trainings "
            "joined (python -m services.vision.ensemble MAIN VETO) and raised by a third (services.vision.danger_raise)"
        ),
    ],
    frames: Annotated[int, typer.Option(help="tuning frames to harvest")] = 16000,
    seed: Annotated[int, typer.Option(help="base seed (generator chunks and the network)")] = 20261123,
    jobs: Annotated[int, typer.Option(help="harvesting processes")] = 2,
    epochs: Annotated[int, typer.Option(help="training epochs")] = 6,
    width: Annotated[
        float, typer.Option(help="the network's channels and hidden units, times the recipe's (round vision24)")
    ] = 1.0,
    cache: Annotated[
        Path | None, typer.Option(help="keep the harvested candidates here (never commit)")
    ] = None,
    printed: Annotated[
        float, typer.Option(help="share of frames with printed words over them (printed.py)")
    ] = 0.0,
    hands: Annotated[
        float,
        typer.Option(help="share of cards with fingers given people's variety (Variation.hand_variety)"),
    ] = 0.0,
    levels: Annotated[
        str,
        typer.Option(
            help="the pyramid the candidates come from, as --detector levels= writes it (default: HARVEST's)"
        ),
    ] = "",
    proposals: Annotated[
        float,
        typer.Option(help="also harvest the proposer's proposals of at least this peak (proposer.py; 0: none)"),
    ] = 0.0,
    arrows: Annotated[
        bool, typer.Option(help="the cluttered chunks also draw arrows (synthetic.EXTRA_DISTRACTORS; round vision21)")
    ] = False,
    hand_drawn: Annotated[
        float, typer.Option(help="share of marks drawn by hand with a pen (Variation.hand_drawn; round vision22)")
    ] = 0.0,
    hand_drawn_shapes: Annotated[
        str, typer.Option(help="the shapes --hand-drawn applies to, comma-separated (round vision22c: TRIANGLE)")
    ] = HAND_DRAWN_SHAPES,
    everyday: Annotated[
        bool,
        typer.Option(help="the cluttered chunks also draw stars, check marks and clock faces (round vision23)"),
    ] = False,
    crossings: Annotated[
        int,
        typer.Option(
            min=0,
            help="the cluttered chunks also draw crossing strokes (two cables crossing, a cable in a loop), listed this "
            "many times among their kinds of clutter (round vision45: 2, vision45c: 6; 0: none)",
        ),
    ] = 0,
    blind: Annotated[
        float,
        typer.Option(
            help="also learn from the blind generator (blind.py): this many of its frames per tuning frame, for "
            "training only (rounds vision29-29b; the bench's blind split then no longer judges the model blind)"
        ),
    ] = 0.0,
    sheen: Annotated[
        float,
        typer.Option(
            min=0.0,
            max=1.0,
            help="share of cards that are glossy, a lamp's reflection over the mark (Variation.sheen; round vision66)",
        ),
    ] = 0.0,
    sheen_shapes: Annotated[
        str,
        typer.Option(help="the marks whose cards --sheen makes glossy, comma-separated (round vision67: X,TRIANGLE)"),
    ] = HAND_DRAWN_SHAPES,
    init: Annotated[
        Path | None,
        typer.Option(
            help="fine-tune: start from this verifier model's network (a joined model's main), its batch norms "
            "frozen, instead of from random weights (round vision67; with a lower --lr and fewer --epochs)",
            exists=True,
            dir_okay=False,
        ),
    ] = None,
    lr: Annotated[float, typer.Option(min=0.0, help="the one-cycle schedule's peak learning rate")] = 3e-3,
    claimed_kept_shapes: Annotated[
        str,
        typer.Option(
            "--claimed-kept",
            help="learn only from candidates claimed as one of these shapes (comma-separated) that the detector's "
            "tests kept, as the second network is asked only about claimed triangles (round vision40: TRIANGLE; "
            "the report too); default: every candidate",
        ),
    ] = "",
    threshold_x: Annotated[float, typer.Option(help="probability a claimed X needs")] = 0.25,
    threshold_o: Annotated[float, typer.Option(help="probability a claimed O needs")] = 0.8,
    threshold_triangle: Annotated[float, typer.Option(help="probability a claimed TRIANGLE needs")] = 0.8,
    loose_x: Annotated[float, typer.Option(help="probability a loose candidate needs to be named X")] = 0.5,
    loose_o: Annotated[float, typer.Option(help="... to be named O")] = 0.95,
    loose_triangle: Annotated[float, typer.Option(help="... to be named TRIANGLE")] = 0.9,
) -> None:
    t0 = time.monotonic()
    if levels:
        try:
            parse_levels(levels)
        except ValueError:
            raise typer.BadParameter(
                f"--levels {levels!r}: levels as FACTOR:WINDOW[:LARGEST], comma-separated"
            ) from None
    for shapes, hint in ((hand_drawn_shapes, "--hand-drawn-shapes"), (sheen_shapes, "--sheen-shapes")):
        try:
            parse_shapes(shapes)
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint=hint) from None
    if blind < 0:
        raise typer.BadParameter(f"--blind {blind}: a share of at least 0")
    try:
        only = parse_shapes(claimed_kept_shapes) if claimed_kept_shapes else ()
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--claimed-kept") from None
    parts = harvest_all(frames, seed, jobs, cache, printed, hands, levels, proposals, arrows, hand_drawn,
                        hand_drawn_shapes, everyday, blind, crossings, sheen, sheen_shapes)
    train, val = split_chunks(parts, blind_chunks(frames, blind))  # the report stays on held-back tuning chunks
    if only:
        train, val = [claimed_kept(p, only) for p in train], [claimed_kept(p, only) for p in val]
    x = np.concatenate([p[0] for p in train])
    c = np.concatenate([p[1] for p in train])
    y = np.concatenate([p[2] for p in train])
    # a network shown only claimed shapes needs only their classes and none (a claimed triangle is seldom an X)
    needed = {CLASSES.index(s) for s in (*only, None)} if only else set(range(len(CLASSES)))
    missing = sorted(needed - set(np.unique(y).tolist()))
    if missing:
        raise SystemExit(f"no training candidates of class {missing}: harvest more frames")
    typer.echo(f"harvested {len(y)} training candidates in {time.monotonic() - t0:.0f} s", err=True)
    try:
        net = fit(x, c, y, seed, epochs, log=lambda m: typer.echo(m, err=True), width=width, init=init, lr=lr)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--init") from None
    export(net, out, (threshold_x, threshold_o, threshold_triangle), (loose_x, loose_o, loose_triangle))
    result = {"train_candidates": len(y), "train_by_class": np.bincount(y, minlength=len(CLASSES)).tolist()}
    result.update(report(Verifier.load(out), val, out))
    result["seconds"] = round(time.monotonic() - t0)
    typer.echo(json.dumps(result, indent=2))


if __name__ == "__main__":
    typer.run(main)
