"""A process pool that refuses to start: the harvest and render caches' tests use it to show a cache was (or was
not) used, since a run that cannot use its cache starts a pool first."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType

import pytest


class PoolRefused(RuntimeError):
    """A harvest or render would have started here: the cache was not used."""


@contextmanager
def no_pool(module: ModuleType) -> Iterator[None]:
    """Inside, `module.ProcessPoolExecutor` raises `PoolRefused`."""

    def refused(*args: object, **kwargs: object) -> None:
        raise PoolRefused

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(module, "ProcessPoolExecutor", refused)
        yield
