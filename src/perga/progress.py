"""Progress of a long command on stderr: tqdm's bar on a terminal; elsewhere (a log file, a
pipe, a batch job) a plain line every ``LINE_EVERY`` seconds and one at the end, never carriage
returns."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any, Protocol

LINE_EVERY = 10.0
"""Seconds of wall time between two progress lines off a terminal."""


class Progress(Protocol):
    """What the commands use of a progress bar (tqdm's names)."""

    n: float
    total: float

    def update(self, n: float = 1) -> Any: ...

    def set_postfix_str(self, s: str = "") -> None: ...

    def close(self) -> None: ...


class LineProgress:
    """Progress as whole lines: ``label: n/total unit (percent), elapsed s[, postfix]``."""

    def __init__(self, total: float, unit: str, label: str, every: float = LINE_EVERY) -> None:
        self.n, self.total, self.unit, self.label, self.every = 0.0, total, unit, label, every
        self.postfix = ""
        self.start = self.last = time.perf_counter()
        self.shown = 0.0

    def update(self, n: float = 1) -> None:
        """Advance by ``n``; print a line if ``every`` seconds have passed since the last."""
        self.n += n
        if time.perf_counter() - self.last >= self.every:
            self._line()

    def set_postfix_str(self, s: str = "") -> None:
        """Text appended to the next lines (e.g. a rate)."""
        self.postfix = s

    def close(self) -> None:
        """The last line, unless the last one printed already said it."""
        if self.n != self.shown:
            self._line()

    def _line(self) -> None:
        now = time.perf_counter()
        share = f" ({self.n / self.total:.0%})" if self.total else ""
        extra = f", {self.postfix}" if self.postfix else ""
        print(
            f"{self.label}: {self.n:g}/{self.total:g} {self.unit}{share}, "
            f"{now - self.start:.0f} s elapsed{extra}",
            file=sys.stderr,
            flush=True,
        )
        self.last, self.shown = now, self.n


class _Silent:
    """No progress at all (``--quiet``)."""

    def __init__(self, total: float) -> None:
        self.n, self.total = 0.0, total

    def update(self, n: float = 1) -> None:
        self.n += n

    def set_postfix_str(self, s: str = "") -> None:
        pass

    def close(self) -> None:
        pass


def counted(bar: Progress) -> Callable[[int, int], None]:
    """A ``progress(done, total)`` callback (the studies' and compare's) that moves ``bar``."""

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.update(done - bar.n)

    return progress


def progress_bar(total: float, unit: str, label: str, quiet: bool, **bar: Any) -> Progress:
    """A progress display of ``total`` ``unit``s: none when ``quiet``, tqdm (with the options
    ``bar``) when stderr is a terminal, :class:`LineProgress` otherwise."""
    if quiet:
        return _Silent(total)
    if not sys.stderr.isatty():
        return LineProgress(total, unit, label)
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, file=sys.stderr, **bar)
