"""JSON encoding of messages on the wire: `application/json;<ModelName>`."""

from __future__ import annotations

from typing import TypeVar

import zenoh
from pydantic import BaseModel, ValidationError

M = TypeVar("M", bound=BaseModel)


class DecodeError(ValueError):
    """A payload that is not a valid message of the expected model."""


def encoding_for(model: type[BaseModel]) -> zenoh.Encoding:
    return zenoh.Encoding.APPLICATION_JSON.with_schema(model.__name__)


def encode(msg: BaseModel) -> bytes:
    return msg.model_dump_json().encode()


def decode(payload: bytes, model: type[M]) -> M:
    try:
        return model.model_validate_json(payload)
    except ValidationError as exc:
        errors = "; ".join(
            f"{'.'.join(str(p) for p in e['loc']) or '<root>'}: {e['msg']}" for e in exc.errors()[:5]
        )
        raise DecodeError(f"invalid {model.__name__}: {errors}") from None
