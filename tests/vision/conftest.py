"""Fixtures shared by the vision tests."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def base_verifier(tmp_path_factory: pytest.TempPathFactory) -> str:
    """The committed verifier's base (`ensemble.unraise`: the model before round vision68b raised the X) as a file for
    `DetectorConfig.verifier_model`. Tests of the detector's own logic whose example the raise changed (an X it now
    finds without the setting the test is about) use it, so that they still test that logic."""
    import onnx

    from services.vision.ensemble import unraise
    from services.vision.verifier import MODEL_PATH

    path = tmp_path_factory.mktemp("verifier") / "base.onnx"
    onnx.save(unraise(onnx.load(str(MODEL_PATH))), str(path))
    return str(path)
