"""Outside programs a test needs (ParaView, xvfb-run, SLURM): where one is missing the test is
skipped, saying which and how to install it, except under ``CI=true``, where CI installs them
(.ci/run) and a missing one is a failure."""

from __future__ import annotations

import os
import shutil

import pytest


def require(*programs: str, install: str) -> None:
    """Skip the calling test (fail it under ``CI=true``) unless every program is on PATH."""
    missing = [p for p in programs if shutil.which(p) is None]
    if not missing:
        return
    why = f"{', '.join(missing)} not installed ({install})"
    if os.environ.get("CI") == "true":
        pytest.fail(f"{why}, and CI=true: CI must have them")
    pytest.skip(why)
