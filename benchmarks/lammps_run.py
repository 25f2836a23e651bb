"""Running Debian's LAMMPS from the benchmarks: one process per run, figures read from its log.

``run`` starts ``lmp`` (or ``mpirun -np k lmp``) on a template of ``benchmarks/lammps/`` with
``-var`` variables, OMP_NUM_THREADS=1, output to a log file; the parsers read the timed figures
LAMMPS prints after each ``run``: "Loop time of T on P procs for S steps with N atoms" (the
wall time of the run's loop, setup excluded), "Neighbor list builds = B" and the share of the
loop in the "Neigh" section of the timing breakdown.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TEMPLATES = Path(__file__).with_name("lammps")
_LOOP = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")
_BUILDS = re.compile(r"^Neighbor list builds = (\d+)", re.M)
_NEIGH = re.compile(r"^Neigh\s*\|.*\|\s*([0-9.]+)\s*$", re.M)


def binary() -> str | None:
    """Path of the LAMMPS executable, or None."""
    for name in ("lmp", "lmp_serial", "lmp_mpi"):
        path = shutil.which(name)
        if path:
            return path
    return None


def version(lmp: str) -> str:
    out = subprocess.run([lmp, "-h"], capture_output=True, text=True).stdout.splitlines()
    return out[1].strip() if len(out) > 1 else "?"


def mpirun() -> str | None:
    return shutil.which("mpirun")


@dataclass
class Run:
    """The timed figures of every ``run`` in one LAMMPS log, in order."""

    log: str
    loops: list[tuple[float, int, int, int]]  # (seconds, procs, steps, atoms)
    builds: list[int]
    neigh_percent: list[float]

    def value(self, key: str) -> float:
        """A number the input printed as 'KEY value'."""
        match = re.search(rf"^{key} (\S+)", self.log, re.M)
        if match is None:
            raise KeyError(key)
        return float(match.group(1))


def run(
    lmp: str, template: str, workdir: Path, variables: dict[str, object], ranks: int = 1
) -> Run:
    """Run ``template`` (a file name in benchmarks/lammps/) in workdir; raises on failure."""
    log = workdir / "log.lammps"
    cmd = [lmp, "-in", str(TEMPLATES / template), "-log", str(log), "-screen", "none"]
    for key, value in variables.items():
        cmd += ["-var", key, str(value)]
    env = {"OMP_NUM_THREADS": "1", "PATH": os.environ.get("PATH", "/usr/bin:/bin")}
    if ranks > 1:
        launcher = mpirun()
        if launcher is None:
            raise RuntimeError("mpirun not found")
        cmd = [launcher, "-np", str(ranks), "--bind-to", "none", *cmd]
        if os.geteuid() == 0:  # Open MPI refuses root without these
            env |= {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    proc = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
    text = log.read_text() if log.exists() else ""
    if proc.returncode != 0 or "ERROR" in text:
        raise RuntimeError(
            f"LAMMPS failed ({proc.returncode}): {' '.join(cmd)}\n{text[-2000:]}\n{proc.stderr}"
        )
    loops = [(float(t), int(p), int(s), int(a)) for t, p, s, a in _LOOP.findall(text)]
    builds = [int(b) for b in _BUILDS.findall(text)]
    neigh = [float(p) for p in _NEIGH.findall(text)]
    return Run(text, loops, builds, neigh)


def read_dump(path: Path) -> dict[str, np.ndarray]:
    """A ``write_dump ... custom id x y vx vy omegaz`` file as arrays sorted by id."""
    lines = path.read_text().splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("ITEM: ATOMS"))
    names = lines[head].split()[2:]
    table = np.loadtxt(lines[head + 1 :], ndmin=2)
    table = table[np.argsort(table[:, names.index("id")])]
    cols = {name: table[:, k] for k, name in enumerate(names)}
    return {
        "x": np.column_stack([cols["x"], cols["y"]]),
        "v": np.column_stack([cols["vx"], cols["vy"]]),
        "w": cols["omegaz"],
    }
