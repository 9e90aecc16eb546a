"""Round vision73's tuning probe (stop 119): one word printed on a card held up - turned any way, tilted up to 40
degrees, 40 to 300 px wide, blurred half the time - over each mark-free tuning frame; the frames with a false mark,
with and without the card. A tuning tool: the words are `services/vision/printed.py`'s, in matplotlib's STIX and
Computer Modern faces, on the tuning generator's frames, never the held-out generator's.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision73_card_words.py SEED FRAMES [KEY=VALUE ...]

Prints one JSON line: the settings, frames with a false mark with the card and without it, false marks by shape with
the card, and the words of the frames the card alone gave a false mark.
"""

from __future__ import annotations

import json
import sys
from collections import Counter

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from services.vision.detector import MarkDetector, parse_settings
from services.vision.printed import WORDS, typefaces
from services.vision.synthetic import SceneGenerator, _card_homography, _paste_warped


def word_card(rng: np.random.Generator, faces: list[str | None]) -> tuple[str, np.ndarray]:
    """A light card with one word in dark ink, borders of 0.05 to 0.35 of the word's longer side (BGR)."""
    word = WORDS[int(rng.integers(len(WORDS)))]
    face = faces[int(rng.integers(len(faces)))]
    font = ImageFont.truetype(face, 120) if face else ImageFont.load_default(size=120)
    x0, y0, x1, y1 = ImageDraw.Draw(Image.new("RGB", (4, 4))).textbbox((0, 0), word, font=font)
    border = rng.uniform(0.05, 0.35, 4) * max(x1 - x0, y1 - y0)
    grey = int(rng.integers(190, 256))
    card = Image.new("RGB", (int(x1 - x0 + border[0] + border[2]), int(y1 - y0 + border[1] + border[3])), (grey,) * 3)
    ink = tuple(int(v) for v in rng.integers(0, 90, 3))
    ImageDraw.Draw(card).text((border[0] - x0, border[1] - y0), word, font=font, fill=ink)
    return word, np.asarray(card)[:, :, ::-1].copy()


def main(seed: int, frames: int, settings: list[str]) -> dict:
    cv2.setNumThreads(1)
    det = MarkDetector(parse_settings(settings))
    faces = typefaces()
    gen, rng = SceneGenerator(seed=seed), np.random.default_rng(seed)
    tally: Counter[str] = Counter()
    words: Counter[str] = Counter()
    for _ in range(frames):
        frame, _ = gen.frame(None)
        word, card = word_card(rng, faces)
        width = float(np.exp(rng.uniform(np.log(40), np.log(300))))
        turn = rng.uniform(-180, 180)
        h = _card_homography(card.shape[1], card.shape[0], (rng.uniform(120, 520), rng.uniform(100, 380)),
                             width / card.shape[1], turn, (rng.uniform(-40, 40), rng.uniform(-40, 40)))
        img = frame.copy()
        _paste_warped(img, card, h)
        if rng.random() < 0.5:
            k = int(rng.integers(1, 4)) * 2 + 1
            img = cv2.GaussianBlur(img, (k, k), 0)
        without, found = det.detect(frame), det.detect(img)
        tally["frames with a false mark without the card"] += bool(without)
        tally["frames with a false mark with the card"] += bool(found)
        tally.update(d.shape.value for d in found)
        if found and not without:
            words[word] += 1
    return {"seed": seed, "frames": frames, "settings": settings, **tally, "words": dict(words.most_common())}


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3:])))
