"""A long run with frequent frames keeps its memory bounded (issue 15, item 7): the bundled
rigid and soft separators for their full 0.5 s with a frame every 0.2 ms (2,500 frames of 300
granules: tables, ParaView files, trajectories streamed to disk), the process's resident memory
sampled from /proc at every progress report. Slow suite."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SAMPLER = """
import json, sys
from pathlib import Path
from perga.case import load_case
from perga.run import prepare_directory, run_case

def rss():
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096 / 2**20

case_path, out = Path(sys.argv[1]), Path(sys.argv[2])
case = load_case(case_path, overrides=["output.every=2e-4"])
prepare_directory(out, overwrite=True)
samples = []
run_case(case, case_path, out, lambda t, d, n: samples.append((t, rss())))
summary = json.loads((out / "summary.json").read_text())
print(json.dumps({"samples": samples, "frames": summary["frames"]}))
"""
GROWTH = 30.0
"""MB the resident memory may grow from a quarter of the run to its end: what a run holds is
O(granules) (recorders stream every frame to disk); a leak of one 300-granule frame (~30 kB)
per frame would add 75 MB over 2,500 frames."""


@pytest.mark.slow
@pytest.mark.parametrize("case", ["separator.toml", "soft-separator.toml"])
def test_a_long_run_with_frequent_frames_keeps_its_memory(case, tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", SAMPLER, str(ROOT / "cases" / case), str(tmp_path / "run")],
        capture_output=True, text=True, check=True, timeout=1200,
    )  # fmt: skip
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["frames"] >= 2500
    samples = result["samples"]
    quarter = next(rss for t, rss in samples if t >= 0.125)
    end = samples[-1][1]
    assert end - quarter < GROWTH, (quarter, end)
