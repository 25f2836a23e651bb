"""The points of a study: a full grid, a Latin hypercube or a scrambled Sobol sequence
(``scipy.stats.qmc``) over the parameters' ranges."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from scipy.stats import qmc

from perga.studies.study_file import Parameter, Study


def axis(parameter: Parameter) -> list[Any]:
    """A parameter's grid values: its ``values``, or ``points`` over its range (linear or log)."""
    if parameter.values is not None:
        return list(parameter.values)
    assert parameter.range is not None
    lo, hi = parameter.range
    if parameter.scale == "log":
        return [float(v) for v in np.geomspace(lo, hi, parameter.points)]
    return [float(v) for v in np.linspace(lo, hi, parameter.points)]


def _scale(unit: np.ndarray, parameters: list[Parameter]) -> np.ndarray:
    """Points of the unit cube mapped onto the ranges (log ranges in log space)."""
    out = np.empty_like(unit)
    for j, p in enumerate(parameters):
        assert p.range is not None
        lo, hi = p.range
        if p.scale == "log":
            out[:, j] = np.exp(np.log(lo) + unit[:, j] * (np.log(hi) - np.log(lo)))
        else:
            out[:, j] = lo + unit[:, j] * (hi - lo)
    return out


def points(study: Study) -> list[dict[str, Any]]:
    """The study's points, each a {case key: value} dict, in a fixed order."""
    keys = list(study.parameters)
    params = [study.parameters[k] for k in keys]
    if study.design == "grid":
        return [
            dict(zip(keys, combo, strict=True))
            for combo in itertools.product(*(axis(p) for p in params))
        ]
    if study.design == "lhs":
        unit = qmc.LatinHypercube(d=len(keys), seed=study.seed).random(study.samples)
    else:
        unit = qmc.Sobol(d=len(keys), scramble=True, seed=study.seed).random(study.samples)
    return [{k: float(v) for k, v in zip(keys, row, strict=True)} for row in _scale(unit, params)]
