"""Marks shared by the soft kernel's tests."""

import pytest

TWO_THREADS = pytest.mark.slow
"""For a test that runs the two-thread kernel: compiling it takes about 85 s on a fresh clone,
paid by whichever such test comes first, so they run with the slow suite."""
