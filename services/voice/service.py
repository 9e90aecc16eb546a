"""The voice service process: joins the bus with its liveliness token and health queryable."""

from __future__ import annotations

from services.runtime import ServiceContext

NAME = "voice"


def serve(ctx: ServiceContext) -> None:
    while not ctx.wait(1.0):
        pass
