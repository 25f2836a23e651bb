"""The Pareto front: hand-built cases with known fronts (two and three objectives, ties,
duplicates, nan rows, one row, every row on the front) and a brute-force reference on random
data."""

from __future__ import annotations

import itertools
import operator

import numpy as np
import pytest

from perga.studies.pareto import pareto_front

nan = np.nan


def _front(values: list[list[float]], senses: list[str]) -> list[int]:
    return pareto_front(np.array(values, dtype=float), senses).tolist()


def test_two_objectives() -> None:
    # throughput up, damage down: (1, 0.1) is beaten by (2, 0.1); (3, 0.3) trades with (2, 0.1)
    values = [[1, 0.1], [2, 0.1], [3, 0.3], [2.5, 0.4], [0.5, 0.05]]
    assert _front(values, ["max", "min"]) == [1, 2, 4]
    assert _front(values, ["min", "max"]) == [0, 3, 4]
    assert _front(values, ["max", "max"]) == [2, 3]


def test_three_objectives() -> None:
    values = [[2, 0.1, 50], [2, 0.1, 40], [3, 0.2, 60], [1, 0.05, 70], [1, 0.2, 80]]
    assert _front(values, ["max", "min", "min"]) == [1, 2, 3]


def test_a_tie_in_one_column_is_not_domination_without_a_strict_gain() -> None:
    # equal in the first column, each better in one of the others
    assert _front([[1, 2, 3], [1, 3, 2]], ["max", "max", "max"]) == [0, 1]
    # equal in two columns, worse in the third: dominated
    assert _front([[1, 2, 3], [1, 2, 4]], ["max", "max", "min"]) == [0]


def test_identical_rows_are_all_kept() -> None:
    values = [[2, 0.1], [2, 0.1], [1, 0.2], [2, 0.1]]
    assert _front(values, ["max", "min"]) == [0, 1, 3]


def test_rows_with_nan_are_never_on_the_front_nor_dominate() -> None:
    values = [[nan, 0.0], [1, 0.2], [5, nan], [0.5, 0.3]]
    assert _front(values, ["max", "min"]) == [1]
    assert _front([[nan, nan]], ["max", "min"]) == []


def test_a_single_row_and_no_rows() -> None:
    assert _front([[1.0, 2.0, 3.0]], ["max", "min", "min"]) == [0]
    assert pareto_front(np.empty((0, 2)), ["max", "min"]).tolist() == []


def test_every_row_on_the_front() -> None:
    values = [[x, x * x] for x in range(6)]  # more throughput costs more damage
    assert _front(values, ["max", "min"]) == list(range(6))


def test_bad_senses_and_shapes_are_refused() -> None:
    with pytest.raises(ValueError, match=r"1: 'maximise'"):
        pareto_front(np.zeros((2, 2)), ["max", "maximise"])
    with pytest.raises(ValueError, match="one per column"):
        pareto_front(np.zeros((2, 3)), ["max", "min"])
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        pareto_front(np.zeros(3), ["max"])


def _reference(values: np.ndarray, senses: list[str]) -> list[int]:
    """O(n²) brute force, written apart from the module: per column a "better" and a "no
    worse" operator, pairs compared element by element in plain Python."""
    better = [operator.gt if s == "max" else operator.lt for s in senses]
    no_worse = [operator.ge if s == "max" else operator.le for s in senses]
    rows = [list(map(float, r)) for r in values]
    complete = [i for i, r in enumerate(rows) if not any(v != v for v in r)]

    def dominates(a: list[float], b: list[float]) -> bool:
        return all(f(x, y) for f, x, y in zip(no_worse, a, b, strict=True)) and any(
            f(x, y) for f, x, y in zip(better, a, b, strict=True)
        )

    return [i for i in complete if not any(dominates(rows[j], rows[i]) for j in complete if j != i)]


@pytest.mark.parametrize("senses", [list(c) for c in itertools.product(["max", "min"], repeat=3)])
def test_random_data_matches_the_brute_force_reference(senses: list[str]) -> None:
    """Small integers, so ties and duplicate rows are common; some nan."""
    rng = np.random.default_rng(20240611)
    for _ in range(20):
        values = rng.integers(0, 5, size=(40, 3)).astype(float)
        values[rng.random(values.shape) < 0.02] = nan
        assert pareto_front(values, senses).tolist() == _reference(values, senses)
