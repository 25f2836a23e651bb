"""The soft kernel's threads: one unless asked or worth it, never more than the free cores, and
what a run used in its summary."""

from __future__ import annotations

import json
import threading
from dataclasses import replace
from pathlib import Path

import numba
import numpy as np
import pytest

from perga.case import load_case
from perga.cli import main
from perga.contact.soft import SoftGranules, chamber, contact_parameters, uniform_table
from perga.contact.soft import threads as t
from perga.engine import Simulation
from perga.model.compile import compile_case

from .marks import TWO_THREADS

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture
def numba_two(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(numba, "get_num_threads", lambda: 2)


@pytest.mark.parametrize(
    ("asked", "granules", "chunks"),
    [(None, t.THREADED_FROM - 1, 1), (None, t.THREADED_FROM, t.AUTO_CHUNKS), (3, 10, 3),
     (1, 100_000, 1)],
)  # fmt: skip
def test_the_chunks_come_from_the_case_alone(asked, granules, chunks):
    assert t.kernel_chunks(asked, granules) == chunks


@pytest.mark.parametrize(("chunks", "free", "used"), [(2, 2, 2), (2, 1, 1), (1, 2, 1), (8, 2, 2)])
def test_threads_never_exceed_the_chunks_the_free_cores_or_numba(numba_two, chunks, free, used):
    assert t.kernel_threads(chunks, free) == used


def test_a_dask_worker_limit_of_one_holds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(numba, "get_num_threads", lambda: 1)
    assert t.kernel_threads(4, 8) == 1


class FakeCores:
    """A ``CoreMonitor`` that reports the free cores of ``looks`` in turn, the last one from then
    on."""

    def __init__(self, looks: list[int]) -> None:
        self.looks = looks
        self.seen = 0

    def free(self) -> int:
        self.seen += 1
        return self.looks[min(self.seen, len(self.looks)) - 1]


def fake_cores(monkeypatch: pytest.MonkeyPatch, *looks: int) -> None:
    """The soft model sees ``looks`` free cores in turn, looking at every machine step."""
    monkeypatch.setattr("perga.contact.soft.model.CoreMonitor", lambda: FakeCores(list(looks)))
    monkeypatch.setattr("perga.contact.soft.model.RECHECK", 0.0)


@TWO_THREADS
def test_a_run_gives_the_same_bytes_on_one_thread_and_on_two(tmp_path, monkeypatch, request):
    """The soft separator with its work in two chunks (solver.threads = 2), run once with one
    core free throughout and once with the free cores going 2, 1, 2, ... from step to step (a
    job started and ended on the other core): the tables and ParaView frames are identical, and
    the summary gives the most threads used at once."""
    held = numba.get_num_threads()
    numba.set_num_threads(2)  # the conftest holds numba at one thread; a run may now use two
    request.addfinalizer(lambda: numba.set_num_threads(held))
    runs = []
    for looks in ([1], [2, 1] * 1000):
        fake_cores(monkeypatch, *looks)
        out = tmp_path / f"free-{len(looks)}"
        args = ["run", str(ROOT / "cases" / "soft-separator.toml"), "-o", str(out), "--quiet",
                "--set", "solver.threads=2", "--set", "solver.duration=0.02"]  # fmt: skip
        assert main(args) == 0
        assert json.loads((out / "summary.json").read_text())["threads"] == max(looks)
        runs.append(out)
    files = sorted(p.relative_to(runs[0]) for p in runs[0].rglob("*") if p.is_file())
    files = [f for f in files if f.name != "summary.json" and f.parts[0] != "checkpoints"]
    assert len(files) > 40
    assert [f for f in files if (runs[0] / f).read_bytes() != (runs[1] / f).read_bytes()] == []


@TWO_THREADS
def test_a_run_follows_the_free_cores(monkeypatch, request):
    """Looking every step, the model's threads follow the free cores (never more than the
    chunks); ``threads`` keeps the most."""
    held = numba.get_num_threads()
    numba.set_num_threads(2)
    request.addfinalizer(lambda: numba.set_num_threads(held))
    fake_cores(monkeypatch, 1, 1, 2, 2, 1, 4)
    spec = compile_case(load_case(ROOT / "cases" / "soft-separator.toml"))
    spec = replace(spec, contact_model=replace(spec.contact_model, threads=2))
    sim = Simulation(spec)
    used = [sim.contacts.granules.threads]
    for _ in range(5):
        sim.step()
        used.append(sim.contacts.granules.threads)
    assert used == [1, 1, 2, 2, 1, 2]
    assert sim.contacts.threads == 2


@pytest.mark.parametrize(("asked", "free", "warned"), [(2, 1, True), (1, 1, False)])
def test_the_summary_says_how_many_threads_and_warns_when_fewer(
    tmp_path, monkeypatch: pytest.MonkeyPatch, asked, free, warned
):
    fake_cores(monkeypatch, free)
    out = tmp_path / "run"
    case = ROOT / "cases" / "soft-single-granule.toml"
    args = ["run", str(case), "-o", str(out), "--quiet", "--set", f"solver.threads={asked}",
            "--set", "solver.duration=0.001"]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["threads"] == 1
    assert any("solver.threads = 2 asked, 1 used" in w for w in summary["warnings"]) == warned


@pytest.mark.parametrize(
    ("value", "ok"), [("1", True), ("256", True), ("0", False), ("257", False)]
)
def test_solver_threads_range(tmp_path, capsys, value, ok):
    case = ROOT / "cases" / "soft-single-granule.toml"
    args = ["run", str(case), "-o", str(tmp_path / "run"), "--quiet",
            "--set", f"solver.threads={value}", "--set", "solver.duration=0.0005"]  # fmt: skip
    assert main(args) == (0 if ok else 2)
    if not ok:
        assert "solver.threads" in capsys.readouterr().err


@TWO_THREADS
def test_granules_added_and_removed_keep_the_chunks(request):
    """A packed bed of discs (a lattice 2.5 % tighter than touching) in a chamber, with its
    work in two chunks, on one thread and on two: granules dropped in and two taken out midway
    leave both on the same bytes (the chunks, not the threads, order every sum: an accumulator
    remade per thread would not)."""
    held = numba.get_num_threads()
    numba.set_num_threads(2)
    request.addfinalizer(lambda: numba.set_num_threads(held))
    row = contact_parameters("linear", 0.6, k_n=2e4, friction=0.4)
    pitch = 0.0039
    rows = [(i * pitch + 0.5 * pitch * (j % 2), j * pitch * 0.866) for i in range(-4, 5)
            for j in range(-4, 2)]  # fmt: skip
    x = np.array(rows)

    def run(threads):
        n = len(x)
        g = SoftGranules(
            x, np.full(n, 2e-3), np.full(n, 1e-4), uniform_table(row), walls=[chamber(0.02)],
            gravity=(0.0, -9.81), threads=threads, chunks=2,
        )  # fmt: skip
        g.step(2000)
        g.add([[0.0, 0.012], [0.006, 0.012]], [2e-3, 2e-3], [1e-4, 1e-4], mat=[0, 0])
        g.step(2000)
        g.remove(np.array([0, 5]))
        g.step(2000)
        return g

    one, two = run(1), run(2)
    assert one.hist.any()  # granules in contact, with tangential springs
    for name in ("x", "v", "w", "f", "tq", "dissipated"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name), err_msg=name)


def test_a_block_that_holds_the_count_spares_the_kernel_the_question(monkeypatch, request):
    """Inside ``numba_threads(n)`` a kernel call on n threads takes the count as held (numba is
    not asked); outside a block, or inside one that holds another count, it asks and runs on
    its own count all the same; after a block the outer count is held again."""
    held = numba.get_num_threads()
    request.addfinalizer(lambda: numba.set_num_threads(held))
    asked, running = [], []
    get, advance = numba.get_num_threads, SoftGranules._bundles

    def counting():
        asked.append(1)
        return get()

    def seen(self, *args):
        running.append(numba.get_num_threads.__wrapped__())
        return advance(self, *args)

    counting.__wrapped__ = get
    monkeypatch.setattr(numba, "get_num_threads", counting)
    monkeypatch.setattr(SoftGranules, "_bundles", seen)
    row = contact_parameters("linear", 0.6, k_n=2e4)
    g = SoftGranules(np.array([[0.0, 0.0], [0.005, 0.0]]), np.full(2, 2e-3), np.full(2, 1e-4),
                     uniform_table(row), walls=[chamber(0.02)], threads=1)  # fmt: skip
    with t.numba_threads(1):
        asked.clear()
        g.step(1)
        assert asked == [] and running == [1]
        with t.numba_threads(2):
            asked.clear()
            g.step(1)
            assert asked == [1] and running == [1, 1]
        asked.clear()
        g.step(1)
        assert asked == [] and running == [1, 1, 1] and t.held_threads() == 1
    asked.clear()
    g.step(1)
    assert asked == [1] and t.held_threads() is None


def test_a_held_count_is_the_holding_threads_alone(request):
    """numba's count is per Python thread, and so is the count a block holds: another Python
    thread (a threaded Dask worker's next task) sees none and asks numba for its own."""
    held = numba.get_num_threads()
    request.addfinalizer(lambda: numba.set_num_threads(held))
    seen = []
    with t.numba_threads(1):
        other = threading.Thread(target=lambda: seen.append(t.held_threads()))
        other.start()
        other.join()
        assert t.held_threads() == 1
    assert seen == [None]
