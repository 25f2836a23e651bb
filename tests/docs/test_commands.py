"""Every command the user docs show runs as written (tests/docs/commands.py says how): a
failing command fails its page's test, naming the page, the block's line and the output."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

import pytest

from tests.docs.commands import (
    CAP,
    ROOT,
    fresh_folder,
    runnable_blocks,
    stand_ins,
    user_pages,
    without_install,
)
from tests.tools import require

EXEMPT = {
    "SLURMCluster": "submits workers to a SLURM queue",
    "PBSCluster": "submits workers to a PBS queue",
    "sbatch ": "submits to a SLURM queue",
    "qsub ": "submits to a PBS queue",
    "--cluster ": "submits workers to a batch system (tests/studies/test_slurm.py runs it)",
}
"""Text that makes a block one the tests cannot run here, and why."""

PARAVIEW = ("paraview ", "pvbatch", "pvpython", "xvfb-run")
PARAVIEW_PROGRAMS = ("paraview", "pvbatch", "xvfb-run")
PAGES = [page for page in user_pages() if runnable_blocks(page)]


def needs_paraview(text: str) -> bool:
    """Whether a block calls ParaView (or its virtual display)."""
    return any(word in text for word in PARAVIEW)


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_every_command_of_the_page_runs_as_written(page, tmp_path):
    """The page's bash and python blocks, in order, in one fresh folder: each exits 0 (runs of
    bundled cases shortened to CAP's simulated seconds)."""
    blocks = runnable_blocks(page)
    if any(needs_paraview(b.text) for b in blocks):
        require(*PARAVIEW_PROGRAMS, install="apt-get install paraview python3-paraview xvfb")
    folder = fresh_folder(tmp_path / "reader")
    env = dict(os.environ, MPLBACKEND="Agg")
    env["PATH"] = f"{stand_ins(tmp_path)}{os.pathsep}{env['PATH']}"
    groups = []
    try:
        for number, block in enumerate(blocks):
            if any(text in block.text for text in EXEMPT):
                continue
            script = tmp_path / f"block{number}.{'py' if block.language == 'python' else 'sh'}"
            if block.language == "python":
                script.write_text(block.text)
                command = [sys.executable, str(script)]
            else:
                script.write_text("set -eo pipefail\n" + without_install(block.text))
                command = ["bash", str(script)]
            log = tmp_path / f"block{number}.log"  # a file: a pipe would wait for what
            with log.open("w") as output:  # a block leaves running (a scheduler) to end
                process = subprocess.Popen(
                    command, cwd=folder, env=env, stdout=output, stderr=subprocess.STDOUT,
                    text=True, start_new_session=True,
                )  # fmt: skip
                groups.append(process.pid)
                process.wait(timeout=900)
            where = f"{page.relative_to(ROOT)}:{block.line}"
            text = log.read_text()[-3000:]
            assert process.returncode == 0, f"{where} exit {process.returncode}:\n{text}"
    finally:
        for group in groups:  # what a block left running (a scheduler, its workers)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(group, signal.SIGTERM)


def test_the_readme_tour_is_a_runnable_block_after_the_two_commands():
    """The README opens with the two commands, then the tour (perga report, compare, new, run,
    sweep, calibrate), all in bash blocks the page test runs."""
    first, tour = runnable_blocks(ROOT / "README.md")[:2]
    assert without_install(first.text).strip().startswith("perga run cases/separator.toml")
    assert "python -m pytest" not in without_install(first.text)
    for command in ("perga report", "perga compare", "perga new", "perga sweep", "perga calibrate"):
        assert command in tour.text
    assert set(CAP) == {"run", "sweep", "window"}


@pytest.mark.parametrize(
    ("line", "status"),
    [
        ("true", 0),
        ("false", 1),
        ("(exit 1)   # a row disagrees: exit 1", 0),
        ("true   # the docs say exit 1, it ends 0", 1),
        ("(exit 2)   # exit 1 declared, 2 is wrong", 1),
        ("python3 -m venv .venv && . .venv/bin/activate && pip install -e . && false", 1),
        ("pip install -e '.[test]' && python -m pytest", 0),
    ],
)
def test_a_block_as_run_keeps_its_exit_status_or_the_one_it_declares(line, status, tmp_path):
    """Install steps go; a command ends as its comment's ``exit N`` says or the block fails."""
    script = tmp_path / "block.sh"
    script.write_text("set -eo pipefail\n" + without_install(line))
    assert subprocess.run(["bash", str(script)], capture_output=True).returncode == status
