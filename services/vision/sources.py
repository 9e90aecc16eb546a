"""Where frames come from: a camera, a video file, a folder or glob of images, or a synthetic scene.

`open_source(spec)` parses HRI_VISION_SOURCE:

    camera:0 | camera:/dev/video0    V4L2 camera; a grabber thread keeps only the newest frame
    path/to/video.mp4                a video file (anything FFmpeg decodes)
    path/to/folder | 'frames/*.png'  images in name order
    synthetic | synthetic:<scenario> rendered marks on cards (scenario: none, the default, holds
                                     nothing up until told; cycle, paper, or a schedule file)

A spec that can never work (an unknown `scheme:`, an unknown synthetic scenario, a bad schedule)
raises `SourceConfigError` at once; a source that cannot be opened now (no camera, missing file)
raises `SourceError` naming the source and the alternatives, and may work on a later attempt.
The synthetic scene's generator (and scikit-image behind it) is imported only for a synthetic source.
"""

from __future__ import annotations

import glob as globlib
import re
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from schemas.messages import Shape
from services.runtime import get_logger

log = get_logger("vision.sources")

ALTERNATIVES = (
    "camera:0, camera:/dev/video0, a video file (clip.mp4), an image folder or glob ('frames/*.png'), "
    "or synthetic (nothing held up until told, as synthetic:none) / synthetic:paper / synthetic:cycle"
)
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm"}


class SourceError(RuntimeError):
    """The source cannot be opened or has failed; the message says which and what else to use."""


class SourceConfigError(SourceError):
    """The spec itself is wrong: retrying cannot help."""


class EndOfStream(Exception):
    """A finite source (file, folder) has delivered its last frame."""


@dataclass(frozen=True)
class Frame:
    image: np.ndarray  # BGR uint8
    stamp: float  # UNIX time of capture
    index: int  # 1-based count of frames delivered by this source


class FrameSource(Protocol):
    spec: str
    default_fps: float | None  # pacing when no cap is given; None: paced by the device

    def open(self) -> None: ...
    def read(self, timeout: float) -> Frame | None: ...
    def fresh(self) -> bool:
        """Whether a live source has a frame newer than the last one read, ready now (the vision loop
        then looks at it between another frame's steps: `lookahead.py`); always False for a file or a
        folder, whose frames are all taken, in order."""
        ...

    def close(self) -> None: ...


def open_source(spec: str, *, loop: bool = False, seed: int = 0) -> FrameSource:
    """Build the source named by `spec` (not yet opened). SourceError if the spec is unusable."""
    spec = spec.strip()
    if not spec:
        raise SourceError(f"empty vision source; use one of: {ALTERNATIVES}")
    if spec.startswith("camera:"):
        if not spec.split(":", 1)[1]:
            raise SourceConfigError(
                f"vision source {spec!r}: camera needs a number or device; use one of: {ALTERNATIVES}"
            )
        return CameraSource(spec)
    if spec == "synthetic" or spec.startswith("synthetic:"):
        source = SyntheticSource(spec, seed=seed)
        source.load_schedule()
        return source
    path = Path(spec).expanduser()
    scheme = re.match(r"^([A-Za-z][A-Za-z0-9+.-]+):", spec)
    if scheme and not path.exists() and "://" not in spec:
        raise SourceConfigError(
            f"vision source {spec!r}: unknown scheme {scheme.group(1)!r}; use one of: {ALTERNATIVES}"
        )
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        return ImageFolderSource(spec, files, loop=loop)
    if any(c in spec for c in "*?["):
        files = sorted(Path(p) for p in globlib.glob(str(path)) if Path(p).suffix.lower() in IMAGE_SUFFIXES)
        return ImageFolderSource(spec, files, loop=loop)
    if not path.exists():
        raise SourceError(f"vision source {spec!r}: no such file or folder; use one of: {ALTERNATIVES}")
    if path.suffix.lower() in IMAGE_SUFFIXES:
        return ImageFolderSource(spec, [path], loop=loop)
    return VideoFileSource(spec, path, loop=loop)


# ---------------------------------------------------------------------- camera
class CameraSource:
    """A V4L2 camera read by a grabber thread that keeps only the newest frame (no growing buffer)."""

    default_fps: float | None = None

    def __init__(self, spec: str, stall_s: float = 2.0) -> None:
        self.spec = spec
        dev = spec.split(":", 1)[1]
        self.device: int | str = int(dev) if dev.isdigit() else dev
        self.stall_s = stall_s
        self._cap: cv2.VideoCapture | None = None
        self._cond = threading.Condition()
        self._latest: Frame | None = None
        self._delivered = 0
        self._failed: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def open(self) -> None:
        if isinstance(self.device, str) and not Path(self.device).exists():
            raise SourceError(f"camera {self.spec}: {self.device} does not exist; use one of: {ALTERNATIVES}")
        cap = cv2.VideoCapture(self.device, cv2.CAP_V4L2)
        if not cap.isOpened():
            cap.release()
            raise SourceError(f"cannot open camera {self.spec} (V4L2); use one of: {ALTERNATIVES}")
        cap.set(cv2.CAP_PROP_BUFFERSIZE, 1)
        self._cap = cap
        self._stop.clear()
        self._failed = None
        self._latest = None
        self._delivered = 0
        self._thread = threading.Thread(target=self._grab, name=f"grab:{self.spec}", daemon=True)
        self._thread.start()

    def _grab(self) -> None:
        assert self._cap is not None
        index = 0
        failures = 0
        while not self._stop.is_set():
            ok, image = self._cap.read()
            stamp = time.time()
            if not ok or image is None:
                failures += 1
                if failures >= 20:
                    with self._cond:
                        self._failed = f"camera {self.spec} stopped delivering frames"
                        self._cond.notify_all()
                    return
                time.sleep(0.05)
                continue
            failures = 0
            index += 1
            with self._cond:
                self._latest = Frame(image, stamp, index)
                self._cond.notify_all()

    def read(self, timeout: float) -> Frame | None:
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                if self._failed:
                    raise SourceError(self._failed)
                if self._latest is not None and self._latest.index > self._delivered:
                    self._delivered = self._latest.index
                    return self._latest
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(left)

    def fresh(self) -> bool:
        with self._cond:
            return self._latest is not None and self._latest.index > self._delivered

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        if self._cap is not None:
            self._cap.release()
            self._cap = None


# ---------------------------------------------------------------------- files
class VideoFileSource:
    def __init__(self, spec: str, path: Path, loop: bool = False) -> None:
        self.spec = spec
        self.path = path
        self.loop = loop
        self.default_fps: float | None = 15.0
        self._cap: cv2.VideoCapture | None = None
        self._index = 0

    def open(self) -> None:
        cap = cv2.VideoCapture(str(self.path))
        if not cap.isOpened():
            cap.release()
            raise SourceError(f"cannot decode video {self.spec}; use one of: {ALTERNATIVES}")
        fps = cap.get(cv2.CAP_PROP_FPS)
        if fps and 0 < fps < 1000:
            self.default_fps = float(fps)
        self._cap = cap

    def read(self, timeout: float) -> Frame | None:
        if self._cap is None:
            raise SourceError(f"video {self.spec} is not open")
        ok, image = self._cap.read()
        if not ok:
            if not self.loop or self._index == 0:
                raise EndOfStream(self.spec)
            self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
            ok, image = self._cap.read()
            if not ok:
                raise EndOfStream(self.spec)
        self._index += 1
        return Frame(image, time.time(), self._index)

    def fresh(self) -> bool:
        return False

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None


class ImageFolderSource:
    def __init__(self, spec: str, files: list[Path], loop: bool = False) -> None:
        self.spec = spec
        self.files = files
        self.loop = loop
        self.default_fps: float | None = 15.0
        self._pos = 0
        self._index = 0

    def open(self) -> None:
        if not self.files:
            raise SourceError(f"no images in {self.spec}; use one of: {ALTERNATIVES}")

    def read(self, timeout: float) -> Frame | None:
        for _ in range(len(self.files)):
            if self._pos >= len(self.files):
                if not self.loop:
                    raise EndOfStream(self.spec)
                self._pos = 0
            path = self.files[self._pos]
            self._pos += 1
            image = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if image is None:
                log.warning("unreadable image skipped", path=str(path))
                continue
            self._index += 1
            return Frame(image, time.time(), self._index)
        raise EndOfStream(self.spec)

    def fresh(self) -> bool:
        return False

    def close(self) -> None:
        pass


# ---------------------------------------------------------------------- synthetic
BUILTIN_SCENARIOS: dict[str, list[tuple[float, Shape | None]]] = {
    "none": [(3600.0, None)],
    "cycle": [(3.0, Shape.X), (3.0, Shape.O), (3.0, Shape.TRIANGLE), (3.0, None)],
    # the paper's experiment (JKROS 12(1), Fig. 12): danger, safe again, danger, safe again
    "paper": [
        (4.0, None),
        (3.0, Shape.X),
        (4.0, None),
        (3.0, Shape.O),
        (4.0, None),
        (3.0, Shape.TRIANGLE),
        (4.0, None),
        (3.0, Shape.O),
    ],
}

DEMO_VARIATION: dict[str, object] = {
    "size": (70.0, 200.0),
    "rotation_deg": 25.0,
    "tilt_deg": 30.0,
    "light": 0.4,
    "dim": (0.7, 1.05),
    "blur": 2.0,
    "noise": 5.0,
    "jpeg": (70, 95),
    "distractors": (2, 5),
    "kinds": ("square", "disc", "text", "face", "cable", "texture", "card"),  # no look-alikes of marks
    "border": (0.2, 0.6),
    "finger_over": 0.0,
    "pale_ink": 0.0,
}
"""A steadier scene than the benchmark's: a person holding a card up to the robot (the fields of
`synthetic.Variation`, kept as plain values so that this module does not import the generator)."""


def parse_schedule(text: str, origin: str = "<schedule>") -> list[tuple[float, Shape | None]]:
    """Lines of `<seconds> <X|O|TRIANGLE|none>`; `#` starts a comment. The schedule repeats."""
    steps: list[tuple[float, Shape | None]] = []
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        try:
            if len(parts) != 2:
                raise ValueError("expected two fields")
            seconds = float(parts[0])
            if seconds <= 0:
                raise ValueError("duration must be positive")
            name = parts[1].upper()
            shape = None if name in ("NONE", "-", "NOTHING") else Shape(name)
        except ValueError as exc:
            raise SourceError(
                f"{origin} line {n}: {raw.strip()!r}: {exc} (write '<seconds> <X|O|TRIANGLE|none>')"
            ) from None
        steps.append((seconds, shape))
    if not steps:
        raise SourceError(f"{origin}: empty schedule")
    return steps


NOISE_PATTERNS = 8
"""Sensor-noise patterns of the synthetic camera, one drawn at random for each frame."""
NOISE_SIGMA = 3.0
"""Their standard deviation, in grey levels."""


class SyntheticSource:
    """Renders the scheduled (or commanded) mark on a card in front of a fixed cluttered backdrop;
    each frame of a scene gets sensor noise, one of `NOISE_PATTERNS` patterns drawn at random.

    `set_shape()` (driven by `SceneCommand` on the bus) overrides the schedule from then on.
    """

    def __init__(
        self,
        spec: str,
        seed: int = 0,
        width: int = 640,
        height: int = 480,
        fps: float = 15.0,
    ) -> None:
        self.spec = spec
        self.default_fps: float | None = fps
        self.scenario = (spec.split(":", 1)[1] if ":" in spec else "") or "none"
        self._seed, self._size = seed, (width, height)
        self._schedule: list[tuple[float, Shape | None]] = []
        self._stills: dict[Shape | None, np.ndarray] = {}
        self._override: tuple[Shape | None] | None = None
        self._noise: list[np.ndarray] = []  # int8 patterns, made when the source opens
        self._pick = np.random.default_rng(seed)
        self._lock = threading.Lock()
        self._t0 = 0.0
        self._index = 0

    def load_schedule(self) -> None:
        """Read the scenario; SourceConfigError if it is neither a built-in nor a readable schedule."""
        if self.scenario in BUILTIN_SCENARIOS:
            self._schedule = BUILTIN_SCENARIOS[self.scenario]
            return
        path = Path(self.scenario).expanduser()
        if not path.is_file():
            raise SourceConfigError(
                f"synthetic scenario {self.scenario!r} is neither a built-in "
                f"({', '.join(BUILTIN_SCENARIOS)}) nor a schedule file; use one of: {ALTERNATIVES}"
            )
        try:
            self._schedule = parse_schedule(path.read_text(errors="replace"), str(path))
        except SourceError as exc:
            raise SourceConfigError(str(exc)) from None

    def open(self) -> None:
        if not self._schedule:
            self.load_schedule()
        if not self._stills:
            from services.vision.synthetic import SKIMAGE_BACKGROUNDS, SceneGenerator, Variation

            variation = Variation(**DEMO_VARIATION)  # type: ignore[arg-type]
            room = (SKIMAGE_BACKGROUNDS[self._seed % len(SKIMAGE_BACKGROUNDS)],)  # one room: less memory
            gen = SceneGenerator(*self._size, seed=self._seed, variation=variation, backgrounds=room)
            # one card pose per shape in front of one backdrop, rendered now (about 40 ms each), so
            # that a new shape shows on the very next frame; each frame adds sensor noise. The
            # generator (and its bank of background images) is not kept.
            backdrop = None
            for shape in (None, *Shape):
                scene = gen.scene(shape)
                backdrop = scene.background if backdrop is None else backdrop
                scene.background = backdrop  # the room stays; only the card changes
                self._stills[shape] = gen.render(scene)[0]
        if not self._noise:
            # Drawing Gaussian noise for a 640x480 frame takes 3-7 ms, which a real camera never
            # spends between the light and the frame; it would sit in every latency measured
            # through this source. So the patterns are drawn once (about 0.9 MB each) and a frame
            # costs one saturating add (under 1 ms).
            rng = np.random.default_rng(self._seed)
            shape3 = (self._size[1], self._size[0], 3)
            self._noise = [np.clip(np.rint(rng.normal(0.0, NOISE_SIGMA, shape3)), -127, 127).astype(np.int8)
                           for _ in range(NOISE_PATTERNS)]
        self._t0 = time.monotonic()

    def set_shape(self, shape: Shape | None) -> None:
        with self._lock:
            self._override = (shape,)

    def current_shape(self) -> Shape | None:
        with self._lock:
            if self._override is not None:
                return self._override[0]
        period = sum(s for s, _ in self._schedule)
        t = (time.monotonic() - self._t0) % period
        for seconds, shape in self._schedule:
            if t < seconds:
                return shape
            t -= seconds
        return self._schedule[-1][1]

    def read(self, timeout: float) -> Frame | None:
        if not self._stills:
            raise SourceError(f"{self.spec} is not open")
        still = self._stills[self.current_shape()]
        stamp = time.time()  # the exposure: the scene as it is now
        noise = self._noise[int(self._pick.integers(len(self._noise)))]
        image = cv2.add(still, noise, dtype=cv2.CV_8U)  # saturating
        self._index += 1
        return Frame(image, stamp, self._index)

    def fresh(self) -> bool:
        return True  # rendered when read: the scene as it is now (the fps cap paces it)

    def close(self) -> None:
        pass
