"""A method wrapped to add its wall time to a running total: how the benchmarks time parts of a
run from inside it."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any


def timed(spent: dict[str, float], part: str, method: Callable[..., Any]) -> Callable[..., Any]:
    """``method`` adding its wall time (``time.perf_counter``, s) to ``spent[part]``."""

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            spent[part] += time.perf_counter() - start

    return wrapper
