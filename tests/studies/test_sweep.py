"""perga sweep on a real Dask cluster: a scheduler and two worker processes started on loopback
as a user would start them (``dask scheduler`` / ``dask worker``); a worker killed mid-study;
a study run again runs nothing, an interrupted one only what is missing."""

from __future__ import annotations

import csv
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from perga.cli import main
from perga.studies.study_file import Parameter, Study, StudyError, study_from_options
from perga.studies.sweep import sweep

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "rebound-test.toml"
METRICS = ["first_impact_restitution", "first_impact_tangential_restitution_contact"]


def _study(points: int = 8, dt: float = 2e-6) -> Study:
    """Rebound shots at ``points`` angles; ``dt`` sets each run's cost (2e-6 s: 1,500 steps)."""
    angles = [round(0.2 + 1.2 * k / (points - 1), 6) for k in range(points)]
    return Study(
        case=CASE,
        parameters={
            "granules.placement.angle": Parameter(values=angles),
            "solver.dt": Parameter(values=[dt]),
        },
        metrics=METRICS,
    )


def _wait_for(path: Path, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while not path.exists():
        if time.monotonic() > end:
            raise TimeoutError(f"{path} did not appear")
        time.sleep(0.1)


@pytest.fixture
def cluster(tmp_path: Path):
    """A scheduler and two single-thread workers (no nanny: a killed worker stays dead), each
    its own process on 127.0.0.1; yields (address, worker processes)."""
    scheduler_file = tmp_path / "scheduler.json"
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
             "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
    ]  # fmt: skip
    try:
        _wait_for(scheduler_file)
        address = json.loads(scheduler_file.read_text())["address"]
        workers = [
            subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                 "--no-nanny", "--no-dashboard", "--host", "127.0.0.1"],
                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )
            for _ in range(2)
        ]  # fmt: skip
        procs += workers
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for p in reversed(procs):
            p.kill()
            p.wait()


def test_sweep_on_a_cluster_survives_a_killed_worker(cluster, tmp_path: Path) -> None:
    """Kill one of the two workers once two rows have come back: every row already received
    stays, the killed worker's run goes to the other, all eight finish, each with its row on
    disk; the metrics equal the impulse law's (e exactly; β to 1e-3 in sliding)."""
    address, workers = cluster
    killed = threading.Event()

    def progress(done: int, total: int) -> None:
        if done >= 2 and not killed.is_set():
            workers[0].send_signal(signal.SIGKILL)
            killed.set()

    study = _study(points=8, dt=5e-7)  # ~1 s a run: the kill lands mid-study
    result = sweep(study, tmp_path / "study", scheduler=address, progress=progress)
    assert killed.is_set() and workers[0].wait(timeout=10) == -signal.SIGKILL
    assert len(result.rows) == 8 and result.failed == 0
    table = pq.read_table(result.path).to_pydict()
    assert table["status"] == ["ok"] * 8
    for row in result.rows:
        assert (Path(row["directory"]) / "row.json").exists()
        assert row["first_impact_restitution"] == pytest.approx(0.7, abs=1e-12)
        theta = row["granules.placement.angle"]
        sliding = 3 * 0.3 * 1.7 / math.tan(theta) - 1  # disc: slip stops unless tan θ > 3f(1+e)
        expected = min(sliding, 0.0)
        beta = row["first_impact_tangential_restitution_contact"]
        assert beta == pytest.approx(expected, abs=2e-3)


def test_a_finished_study_runs_nothing_and_an_interrupted_one_only_what_is_missing(
    tmp_path: Path,
) -> None:
    """A local cluster of two worker processes. Run again: nothing runs, the same rows. Then
    three runs are made to look unfinished (their row.json removed, as a run cut short by
    Ctrl-C or a dead machine leaves it): only those three run."""
    study, out = _study(points=6), tmp_path / "study"
    first = sweep(study, out, workers=2)
    assert (first.ran, first.reused, first.failed) == (6, 0, 0)
    with (out / "results.csv").open(newline="") as stream:  # the same rows, for a spreadsheet
        spreadsheet = list(csv.DictReader(stream))
    assert [r["key"] for r in spreadsheet] == [r["key"] for r in first.rows]
    assert [float(r["first_impact_restitution [-]"]) for r in spreadsheet] == [
        r["first_impact_restitution"] for r in first.rows
    ]
    assert "wall_time [s]" in spreadsheet[0] and "granules.placement.angle" in spreadsheet[0]
    again = sweep(study, out, workers=2)
    assert (again.ran, again.reused) == (0, 6)
    assert again.rows == first.rows
    for row in first.rows[1::2]:
        (Path(row["directory"]) / "row.json").unlink()
    resumed = sweep(study, out, workers=2)
    assert (resumed.ran, resumed.reused) == (3, 3)
    same = ["key", "granules.placement.angle", *METRICS, "status"]
    assert [{k: r[k] for k in same} for r in resumed.rows] == [
        {k: r[k] for k in same} for r in first.rows
    ]


@pytest.mark.slow  # a study on workers, interrupted and run again: 10-12 s
def test_ctrl_c_leaves_a_study_that_resumes(tmp_path: Path) -> None:
    """SIGINT to ``perga sweep`` once the study has received a row (its table is first written
    then): exit 130 and a readable table of the rows received; the same command again runs only
    the runs that left no row on disk (a row written by a worker but not yet received is found,
    not run again)."""
    out = tmp_path / "study"
    command = [sys.executable, "-m", "perga.cli", "sweep", str(CASE), "-o", str(out),
               "--set", "granules.placement.angle=0.2:1.4:12", "--set", "solver.dt=5e-7",
               "--metric", METRICS[0], "--workers", "2", "--quiet"]  # fmt: skip
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + 120
    while not (out / "results.parquet").exists():
        assert proc.poll() is None and time.monotonic() < end, proc.communicate()
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "run the same command again to resume" in err
    received = len(pq.read_table(out / "results.parquet"))
    on_disk = len(list((out / "runs").glob("*/row.json")))
    assert 1 <= received <= on_disk < 12, (received, on_disk)
    finished = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert finished.returncode == 0, finished.stderr
    assert f"({12 - on_disk} run now, {on_disk} found finished" in finished.stdout
    table = pq.read_table(out / "results.parquet").to_pydict()
    assert table["status"] == ["ok"] * 12


def test_bad_study_files_exit_2_naming_the_field(tmp_path: Path, capsys) -> None:
    """Unknown key, unknown metric, a parameter that is not a case key, a range with LO >= HI:
    exit 2, each message naming the file and the field."""
    cases = {
        "color = 1": "color: unknown key",
        'metrics = ["bogus"]': "unknown metric 'bogus'",
        '"rotor.rpmm" = { values = [1.0] }': "rotor.rpmm: unknown key; did you mean 'rpm'?",
        '"rotor.rpm" = { range = [2.0, 2.0] }': "range needs LO < HI",
        '"rotor.rpm" = { range = [3.0, 2.0] }': "range needs LO < HI",
    }
    for line, expected in cases.items():
        study = tmp_path / "study.toml"
        head, params = [f'case = "{CASE}"'], ['"granules.placement.angle" = { values = [0.3] }']
        metrics = 'metrics = ["first_impact_restitution"]'
        if line.startswith("metrics"):
            metrics = line
        elif line.startswith('"'):
            params = [line]
        else:
            head.append(line)
        study.write_text("\n".join([*head, metrics, "[parameters]", *params]) + "\n")
        assert main(["sweep", str(study), "-o", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert str(study) in err and expected in err, (line, err)


def test_a_valid_range_is_accepted(tmp_path: Path) -> None:
    """The other side of the LO < HI limit: LO just below HI gives a study."""
    from perga.studies.study_file import load_study

    study = tmp_path / "study.toml"
    study.write_text(
        f'case = "{CASE}"\nmetrics = ["first_impact_restitution"]\n[parameters]\n'
        '"rotor.omega" = { range = [1e-4, 1.0001e-4], points = 2 }\n'
    )
    assert load_study(study).parameters["rotor.omega"].range == (1e-4, 1.0001e-4)


@pytest.mark.parametrize("digits", [4300, 4301])
def test_a_sweep_value_of_thousands_of_digits_is_refused(digits: int) -> None:
    """Up to Python's limit (4300 digits) a value out of the key's range, beyond it a number
    too long to read: a StudyError naming the --set either way, never a traceback."""
    case = Path(__file__).resolve().parents[2] / "cases" / "rebound-test.toml"
    text = f"granules.placement.angle=0.5,{'9' * digits}"
    with pytest.raises(StudyError) as caught:
        study_from_options(case, [text], ["first_impact_restitution"])
    (problem,) = caught.value.problems
    if digits > 4300:
        assert problem.startswith(f"--set {text[:77]}...: an integer of more than 4300 digits")
    else:
        assert problem.startswith("--set: ") and "granules.placement.angle: " in problem
        assert "[angle of the path, rad" in problem
    assert len(problem) < 400


@pytest.mark.parametrize(
    ("values", "refused"), [("0.2,1.5", False), ("0.2,1.6", True), ("0.2:1.6:3", True)]
)
def test_every_value_of_a_sweep_is_checked_not_only_the_first(values, refused) -> None:
    """The largest of a sweep's values, or a range's end, out of the key's range is refused
    before any run (the first value alone was checked)."""
    case = Path(__file__).resolve().parents[2] / "cases" / "rebound-test.toml"
    try:
        study_from_options(
            case, [f"granules.placement.angle={values}"], ["first_impact_restitution"]
        )
    except StudyError as exc:
        assert refused and "granules.placement.angle: " in exc.problems[0], exc.problems
    else:
        assert not refused
