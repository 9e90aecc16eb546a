"""A two-letter word on a card held up at an angle (round vision73, `DetectorConfig.text_twin`): today its O or X is a
mark, since the turned text-line test takes a lone neighbour for the other letter only if its upright box is within a
tenth of the candidate's size, and a turned O, K or N differ by more. With `text_twin` a lone neighbour further off in
size counts too, but only where it is printed on the candidate's own paper (`TWIN_PAPER`): an X on its card beside a
letter on the page behind the card stays a mark."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, ImageDraw, ImageFont

import services.vision.detector as detector
from services.vision.detector import DetectorConfig, MarkDetector, parse_settings
from services.vision.printed import typefaces
from services.vision.synthetic import _card_homography, _paste_warped


def _face(name: str) -> str:
    found = [f for f in typefaces() if f and Path(f).name == name]
    assert found, f"matplotlib's {name} (it comes with the test extra's zenoh-cli)"
    return found[0]


def _word_on_card(word: str, turn: float) -> np.ndarray:
    """`word` in STIX bold, dark on a light card 160 px wide, turned by `turn` degrees, on a grey wall."""
    font = ImageFont.truetype(_face("STIXGeneralBol.ttf"), 120)
    x0, y0, x1, y1 = ImageDraw.Draw(Image.new("RGB", (4, 4))).textbbox((0, 0), word, font=font)
    pad = 25
    card = Image.new("RGB", (x1 - x0 + 2 * pad, y1 - y0 + 2 * pad), (235, 235, 235))
    ImageDraw.Draw(card).text((pad - x0, pad - y0), word, font=font, fill=(30, 30, 30))
    patch = np.asarray(card)[:, :, ::-1].copy()
    img = np.full((480, 640, 3), 110, np.uint8)
    _paste_warped(img, patch, _card_homography(patch.shape[1], patch.shape[0], (320, 240), 160 / patch.shape[1], turn,
                                               (0.0, 0.0)))
    return img


def _x_card_beside_a_letter_on_the_page() -> np.ndarray:
    """An X on a light card, and an R of about its size on the grey page behind the card, in line with it."""
    img = Image.new("RGB", (640, 480), (170, 170, 170))
    d = ImageDraw.Draw(img)
    cx, cy = 300, 240
    d.rectangle((cx - 48, cy - 48, cx + 48, cy + 48), fill=(240, 240, 240))
    d.line((cx - 30, cy - 30, cx + 30, cy + 30), fill=(30, 30, 30), width=10)
    d.line((cx - 30, cy + 30, cx + 30, cy - 30), fill=(30, 30, 30), width=10)
    at = (cx + 85 * math.cos(math.radians(20)), cy + 85 * math.sin(math.radians(20)))
    d.text(at, "R", font=ImageFont.truetype(_face("STIXGeneral.ttf"), 115), fill=(30, 30, 30), anchor="mm")
    return cv2.GaussianBlur(np.asarray(img)[:, :, ::-1].copy(), (3, 3), 0)


@pytest.mark.parametrize(("word", "turn"), [("OK", 15), ("NO", 30), ("ON", 120), ("XO", 60), ("XO", 165)])
def test_a_turned_two_letter_word_on_a_card_is_no_mark_with_text_twin(word: str, turn: float) -> None:
    img = _word_on_card(word, turn)
    assert MarkDetector(DetectorConfig(text_twin=0.0)).detect(img), "without it, the word's O or X is taken for a mark"
    assert MarkDetector(parse_settings(["text_twin=0.3"])).detect(img) == []


def test_an_x_beside_a_letter_printed_on_another_paper_stays_a_mark(monkeypatch: pytest.MonkeyPatch) -> None:
    img = _x_card_beside_a_letter_on_the_page()
    found = MarkDetector(DetectorConfig(text_twin=0.3)).detect(img)
    assert [d.shape.value for d in found] == ["X"]
    assert [d.shape.value for d in MarkDetector(DetectorConfig(text_twin=0.0)).detect(img)] == ["X"]
    monkeypatch.setattr(detector, "TWIN_PAPER", 1.0)  # any paper: the R would be the X's twin
    assert MarkDetector(DetectorConfig(text_twin=0.3)).detect(img) == []


def test_text_twin_is_off_by_default_and_a_share_below_one() -> None:
    assert DetectorConfig().text_twin == 0.0
    for bad in ("-0.1", "1", "2"):
        with pytest.raises(ValueError, match="text_twin"):
            parse_settings([f"text_twin={bad}"])
