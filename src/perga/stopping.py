"""Stop signals: SIGINT (Ctrl-C), SIGTERM (a batch system's or ``kill``'s) and SIGHUP (a closed
terminal) all stop perga the same way, as a :class:`StopSignal`, never by killing the process
mid-write.

:func:`raise_on_stop_signals` makes each of them raise :class:`StopSignal` wherever Python is
(the command line's default). Where an exception at an arbitrary point would do harm,
:class:`StopRequest` defers them to a safe point instead: while modules are imported (an
exception inside a library's import can leave it half made), and inside a run, to the next step
boundary (a KeyboardInterrupt raised inside a Pymunk callback is swallowed by cffi, and one
raised in the middle of a frame's writes would cut a table row). A second signal while one is
pending raises at once (a step that never ends can still be stopped). A :class:`StopSignal`
raised where Python swallows exceptions (a garbage-collector callback, such as the one
``distributed`` installs, or a ``__del__``) is kept and raised by :func:`raise_swallowed` at the
next safe point. Standard library only, so that the command line can import it before anything
heavy.
"""

from __future__ import annotations

import signal
import sys
import threading
from types import FrameType

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class StopSignal(KeyboardInterrupt):
    """A stop signal was received: ``signum``; ``name`` such as 'SIGTERM'. A KeyboardInterrupt, so
    that code which cleans up after Ctrl-C cleans up after every stop signal."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        self.name = signal.Signals(signum).name
        super().__init__(self.name)

    @property
    def exit_status(self) -> int:
        """The shell's status for a process stopped by this signal: 128 + its number."""
        return 128 + self.signum


def exit_status(stop: KeyboardInterrupt) -> int:
    """The exit status after ``stop``: 128 + the signal's number (130 for a bare Ctrl-C)."""
    return stop.exit_status if isinstance(stop, StopSignal) else 128 + signal.SIGINT


def describe(stop: KeyboardInterrupt) -> str:
    """What stopped a run, for its summary: 'stopped by SIGTERM', or by Ctrl-C."""
    if isinstance(stop, StopSignal) and stop.signum != signal.SIGINT:
        return f"stopped by {stop.name}"
    return "stopped by the user (Ctrl-C, SIGINT)"


def _raise(signum: int, _frame: FrameType | None) -> None:
    raise StopSignal(signum)


_swallowed: list[int] = []
"""Stop signals whose StopSignal Python swallowed (:func:`_keep_swallowed`), oldest first."""


def _keep_swallowed(unraisable: sys.UnraisableHookArgs) -> None:
    """``sys.unraisablehook``: keep a swallowed StopSignal for :func:`raise_swallowed`; report
    anything else as Python would."""
    if isinstance(unraisable.exc_value, StopSignal):
        _swallowed.append(unraisable.exc_value.signum)
    else:
        sys.__unraisablehook__(unraisable)


def raise_swallowed() -> None:
    """Raise, as :class:`StopSignal`, a stop signal that Python swallowed, if any."""
    if _swallowed:
        signum = _swallowed[0]
        _swallowed.clear()
        raise StopSignal(signum)


def raise_on_stop_signals() -> None:
    """From now on each stop signal raises :class:`StopSignal` (main thread only), and one
    raised where Python swallows exceptions is kept for :func:`raise_swallowed`."""
    if threading.current_thread() is threading.main_thread():
        for signum in STOP_SIGNALS:
            signal.signal(signum, _raise)
        sys.unraisablehook = _keep_swallowed


class StopRequest:
    """While entered, a stop signal sets :attr:`signum`, which :meth:`check` raises as
    :class:`StopSignal` (call it where stopping is safe: between steps, after imports); a second
    signal raises at once. The previous handlers come back on exit. Main thread only (elsewhere
    a no-op)."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._previous: dict[int, object] = {}

    def __enter__(self) -> StopRequest:
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def _handle(self, signum: int, _frame: FrameType | None) -> None:
        if self.signum is not None:
            raise StopSignal(signum)
        self.signum = signum

    def check(self) -> None:
        """Raise the pending stop signal, if any."""
        if self.signum is not None:
            raise StopSignal(self.signum)

    def __exit__(self, *_exc: object) -> None:
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)  # type: ignore[arg-type]
        self._previous.clear()
