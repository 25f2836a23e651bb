"""The README's first command (its perga part) and quick tour as a user runs them, uncapped, one
line at a time in a fresh folder: the wall time of each, the machine and its load (the figures
the README quotes).

    python benchmarks/readme_tour.py           # ~5 min on a 2-core machine
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.docs.commands
from tests.docs.commands import ROOT, fresh_folder, runnable_blocks, stand_ins, without_install


def cpu_name() -> str:
    """The processor's model name (Linux), or the platform's."""
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor()


def main() -> None:
    first, tour = runnable_blocks(ROOT / "README.md")[:2]
    typed = [first.text.splitlines()[0], *tour.text.replace("\\\n", " ").splitlines()]
    lines = [(line, without_install(line).strip()) for line in typed]
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores; load before {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = fresh_folder(Path(tmp) / "reader")
        env = dict(os.environ, MPLBACKEND="Agg")
        bin_dir = stand_ins(Path(tmp))
        (bin_dir / "perga").unlink()  # the installed perga, uncapped; ParaView loads and exits
        env["PATH"] = f"{bin_dir}{os.pathsep}{env['PATH']}"
        print("| command | wall time (s) |\n|---|---:|")
        for shown, line in lines:
            start = time.perf_counter()
            done = subprocess.run(
                ["bash", "-eo", "pipefail", "-c", line], cwd=folder, env=env, capture_output=True
            )
            seconds = time.perf_counter() - start
            status = "" if done.returncode == 0 else f" (failed: exit {done.returncode})"
            command = " ".join(without_install(shown.split("#")[0]).split())
            print(f"| `{command}` | {seconds:.1f}{status} |", flush=True)
    print(f"load after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
