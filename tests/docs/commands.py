"""The commands the user docs show, as the tests run them: the ``bash`` and ``python`` blocks of
README.md and docs/ (not docs/dev/ nor docs/architecture.md, the developers'), in page order,
in a fresh folder holding copies of the repository's cases/, geometry/, examples/ and
postprocess/, through two stand-ins put first on PATH:

- ``perga``: the installed command, with ``--set solver.duration=CAP`` added to a ``run``,
  ``sweep`` or ``window`` of a case whose own duration is longer than the cap (a test's
  budget, not the docs': the cap is printed);
- ``paraview``: the GUI loads the state under ``xvfb-run`` and exits (``--exit``); a Python
  error in it is a failure.

The install lines (a virtual environment, ``pip install``) are left out: the tests run in the
installed environment; so is ``python -m pytest`` (the suite running itself).
"""

from __future__ import annotations

import re
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
COPIED = ("cases", "geometry", "examples", "postprocess")
"""The repository folders a page's commands may name, copied into its fresh folder."""

CAP = {"run": 0.5, "sweep": 0.05, "window": 0.05}
"""Simulated seconds (s) a ``perga`` subcommand's runs are shortened to, when longer."""

INSTALL = re.compile(
    r"^\s*(python3? -m venv\b|\. \.venv/bin/activate|source \.venv/bin/activate|pip install\b"
    r"|python3? -m pip install\b|python3? -m pytest\b|git clone\b|cd perga\b)"
)
"""A step of the install (or the suite itself): not run by the tests."""

FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)


@dataclass(frozen=True)
class Block:
    """A fenced code block of a page: its language, text and first line (1-based)."""

    language: str
    text: str
    line: int


def user_pages() -> list[Path]:
    """README.md and the user docs (docs/ but its dev/ and architecture.md), in a fixed order."""
    docs = ROOT / "docs"
    pages = sorted(docs.rglob("*.md"))
    users = [
        p for p in pages if p.relative_to(docs).parts[0] != "dev" and p.name != "architecture.md"
    ]
    return [ROOT / "README.md", *users]


def runnable_blocks(page: Path) -> list[Block]:
    """The ``bash``/``sh``/``python`` blocks of ``page``, in order."""
    text = page.read_text(encoding="utf-8")
    return [
        Block(match.group(1), match.group(2), text.count("\n", 0, match.start()) + 1)
        for match in FENCE.finditer(text)
        if match.group(1) in ("bash", "sh", "python")
    ]


DECLARED_EXIT = re.compile(r"#.*\bexit (\d+)\b")
"""A command's comment that names the exit status it ends with (``# ... exit 1: ...``)."""


def without_install(script: str) -> str:
    """``script`` (a bash block) as the tests run it: a ``&&`` chain loses its install links, a
    line that is all install goes, and a line whose comment declares ``exit N`` must end so."""
    lines = []
    for line in script.replace("\\\n", " ").splitlines():
        links = [link for link in line.split("&&") if not INSTALL.match(link)]
        if not links:
            continue
        line = "&&".join(links).strip()
        if declared := DECLARED_EXIT.search(line):
            command, status = line[: declared.start()].strip(), declared.group(1)
            line = (
                f"set +e; {command}; status=$?; set -e; [ $status -eq {status} ] || "
                f'{{ echo "exit $status, the docs say {status}: {command}" >&2; exit 1; }}'
            )
        lines.append(line)
    return "\n".join(lines) + "\n"


PERGA_STAND_IN = '''#!{python}
"""perga as installed, with the tests' duration cap (tests/docs/commands.py)."""
import sys
import tomllib
from pathlib import Path

from perga.cli import main

CAP = {cap!r}


def capped(argv):
    """argv with the duration cap added to a run, sweep or window of a longer case."""
    if not argv or argv[0] not in CAP or any(a.startswith("solver.duration=") for a in argv):
        return argv
    case = next((Path(a) for a in argv[1:] if a.endswith(".toml") and Path(a).is_file()), None)
    if case is None:
        return argv
    duration = tomllib.loads(case.read_text()).get("solver", {{}}).get("duration")
    if duration is None or duration <= CAP[argv[0]]:
        return argv
    print(f"[docs test: {{case}} shortened to {{CAP[argv[0]]}} s]", file=sys.stderr)
    return [*argv, "--set", f"solver.duration={{CAP[argv[0]]}}"]


if __name__ == "__main__":  # Dask's worker processes import this file again
    sys.exit(main(capped(sys.argv[1:])))
'''

PARAVIEW_STAND_IN = """#!/usr/bin/env bash
# the ParaView GUI loads the state and exits (tests/docs/commands.py)
empty="$(mktemp --suffix=.xml)"
printf '<?xml version="1.0" ?>\\n<pqevents>\\n</pqevents>\\n' > "$empty"
out="$(xvfb-run -a -s '-screen 0 1280x1024x24' \\
    {paraview} --dr "$@" --test-script="$empty" --exit 2>&1)"
status=$?
echo "$out"
if echo "$out" | grep -q Traceback; then exit 1; fi
exit $status
"""


def stand_ins(folder: Path) -> Path:
    """The folder of the stand-ins (``perga``, and ``paraview`` where it is installed)."""
    bin_dir = folder / "bin"
    bin_dir.mkdir()
    perga = bin_dir / "perga"
    perga.write_text(PERGA_STAND_IN.format(python=sys.executable, cap=CAP))
    perga.chmod(0o755)
    if real := shutil.which("paraview"):
        paraview = bin_dir / "paraview"
        paraview.write_text(PARAVIEW_STAND_IN.format(paraview=real))
        paraview.chmod(0o755)
    return bin_dir


def fresh_folder(folder: Path) -> Path:
    """``folder`` with copies of the repository folders the docs' commands name."""
    for name in COPIED:
        shutil.copytree(ROOT / name, folder / name, ignore=shutil.ignore_patterns("__pycache__"))
    return folder
