"""Study files (``perga sweep STUDY.toml``): the base case, the parameters to vary, the design
of the points, the replicates and the metrics to keep. Checked like case files: every problem
at once, each naming the file, the field and what is allowed; ``StudyError`` carries them.

```toml
case = "../cases/rebound-test.toml"     # relative to the study file
design = "grid"                         # grid | lhs | sobol
samples = 16                            # points of an lhs or sobol design
replicates = 2                          # runs per point, each with its own seed
seed = 0                                # seeds the design and the replicates' seeds
metrics = ["first_impact_restitution", "first_impact_rebound_angle_centre"]

[parameters]
"granules.placement.angle" = { values = [0.2, 0.6, 1.0, 1.3] }
"contacts.granule-hammer.friction" = { range = [0.1, 0.5], points = 3 }   # grid: points
```

A parameter is a case key (:mod:`perga.case.overrides`) with ``values``, or a ``range`` [LO, HI]
(LO < HI) sampled by the design (``points`` of them on a grid, linearly or with
``scale = "log"``). Each point's case is checked like a file before anything runs.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from perga.case import CaseError
from perga.case.load import overridden, read_case_data, validate_case
from perga.case.names import unknown_key
from perga.case.overrides import NumberTooLong, parse_toml, parse_value
from perga.model.compile import check
from perga.stats.metrics import METRICS, parse_metric


class StudyError(Exception):
    """A study or data file that cannot be used; ``problems`` names each problem."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Parameter(_Strict):
    """One varied case key: ``values``, or a ``range`` the design samples."""

    values: list[float | int | str | bool] | None = Field(
        None, min_length=1, description="the values to run"
    )
    range: tuple[float, float] | None = Field(None, description="[LO, HI], LO < HI")
    points: int = Field(3, ge=2, le=1000, description="grid points over a range, in [2, 1000]")
    scale: Literal["linear", "log"] = Field("linear", description="spacing of a range's points")

    @model_validator(mode="after")
    def _one_of(self) -> Parameter:
        if (self.values is None) == (self.range is None):
            raise ValueError("give exactly one of values = [...] or range = [LO, HI]")
        if self.range is not None:
            lo, hi = self.range
            if not lo < hi:
                raise ValueError(f"range needs LO < HI (got [{lo}, {hi}])")
            if self.scale == "log" and lo <= 0:
                raise ValueError(f"a log range needs LO > 0 (got {lo})")
        return self


class Study(_Strict):
    """A sweep of a case over parameters (module doc)."""

    case: Path = Field(description="the base case file, relative to the study file")
    parameters: dict[str, Parameter] = Field(min_length=1, description="case key -> values")
    design: Literal["grid", "lhs", "sobol"] = Field("grid", description="grid, lhs or sobol")
    samples: int = Field(16, ge=1, le=100_000, description="points of an lhs/sobol design")
    replicates: int = Field(1, ge=1, le=1000, description="runs per point, own seeds, [1, 1000]")
    seed: int = Field(0, ge=0, description="seed of the design and of the replicates' seeds")
    metrics: list[str] = Field(min_length=1, description="metric names (perga.stats.metrics)")

    @model_validator(mode="after")
    def _ranges_need_design(self) -> Study:
        if self.design != "grid" and any(p.values is not None for p in self.parameters.values()):
            raise ValueError(f"design '{self.design}' samples ranges: give every parameter a range")
        return self


def _describe(error: dict) -> str:
    loc = ".".join(str(p) for p in error["loc"])
    if error["type"] == "extra_forbidden":
        options = [*Study.model_fields] if len(error["loc"]) == 1 else [*Parameter.model_fields]
        return f"{loc}: {unknown_key(str(error['loc'][-1]), options)}"
    got = f" (got {error['input']!r})" if "input" in error and error["type"] != "missing" else ""
    return f"{loc or '(top level)'}: {error['msg'].removeprefix('Value error, ')}{got}"


def check_metrics(names: list[str], where: str) -> list[str]:
    """Problems with metric names, each naming ``where``."""
    problems = []
    for name in names:
        try:
            parse_metric(name)
        except ValueError as exc:
            problems.append(f"{where}: {exc}")
    return problems


def check_keys(case_path: Path, keys: dict[str, object], where: str) -> list[str]:
    """Problems of case keys set to example values: applied to the case and checked like the
    file, so an unknown key or a value out of range is named as the case file would name it."""
    try:
        data = read_case_data(case_path)
        check(validate_case(overridden(data, [f"{k}={v}" for k, v in keys.items()], case_path),
                            case_path))  # fmt: skip
    except CaseError as exc:
        return [f"{where}: {p}" for p in exc.problems]
    return []


def extremes(parameter: Parameter) -> list[object]:
    """The values of ``parameter`` that stand for all in a check of the case: a range's ends,
    the smallest and largest of its numbers and each of its other values (a key's limits are
    intervals)."""
    if parameter.range is not None:
        return list(parameter.range)
    values = parameter.values or []
    numbers = [v for v in values if isinstance(v, int | float) and not isinstance(v, bool)]
    others = [v for v in dict.fromkeys(values) if v not in numbers]
    return [*dict.fromkeys([min(numbers), max(numbers)] if numbers else []), *others]


def check_parameters(case_path: Path, parameters: dict[str, Parameter], where: str) -> list[str]:
    """Problems of the case with each parameter at each of its :func:`extremes`, the others at
    their first value; each problem once."""
    first = {k: extremes(p)[0] for k, p in parameters.items()}
    problems = check_keys(case_path, first, where)
    for key, parameter in parameters.items():
        for value in extremes(parameter)[1:]:
            problems += check_keys(case_path, {**first, key: value}, where)
    return list(dict.fromkeys(problems))


def load_study(path: str | Path) -> Study:
    """A checked study: schema, metric names, the base case, and every parameter's key with its
    :func:`extremes` (StudyError listing every problem)."""
    path = Path(path)
    try:
        data = parse_toml(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise StudyError([f"{path}: cannot read ({exc})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise StudyError([f"{path}: not valid TOML: {exc}"]) from None
    try:
        study = Study.model_validate(data)
    except ValidationError as exc:
        raise StudyError([f"{path}: {_describe(e)}" for e in exc.errors()]) from None
    study = study.model_copy(update={"case": (path.parent / study.case).resolve()})
    problems = check_metrics(study.metrics, f"{path}: metrics")
    try:
        is_file = study.case.is_file()
    except OSError as exc:  # a name the file system refuses (too long, ...)
        problems.append(f"{path}: case: cannot use {str(study.case)[:80]}…: {exc.strerror}")
        is_file = None
    if is_file is False:
        problems.append(f"{path}: case: no such file {study.case}")
    elif is_file:
        problems += check_parameters(study.case, study.parameters, f"{path}: parameters")
    if problems:
        raise StudyError(problems)
    return study


def parse_values(text: str, where: str) -> Parameter:
    """``KEY=V1,V2,...`` or ``KEY=LO:HI:N`` (N grid points) -> the parameter (StudyError)."""
    parts = text.split(":")
    if len(parts) == 3:
        try:
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
            return Parameter(range=(lo, hi), points=n)
        except (ValueError, ValidationError) as exc:
            message = exc.errors()[0]["msg"] if isinstance(exc, ValidationError) else str(exc)
            raise StudyError([f"{where}: LO:HI:N needs LO < HI and N >= 2 ({message})"]) from None
    try:
        return Parameter(values=[parse_value(v.strip()) for v in text.split(",")])
    except NumberTooLong as exc:
        raise StudyError([f"{where}: {exc}"]) from None
    except ValidationError:
        raise StudyError(
            [f"{where}: a study's values are numbers, strings or booleans (V1,V2,... or "
             "LO:HI:N); set a whole table in the case file"]
        ) from None  # fmt: skip


def study_from_options(
    case: Path, sets: list[str], metrics: list[str], replicates: int = 1, seed: int = 0
) -> Study:
    """The study of ``perga sweep CASE --set KEY=VALUES ... --metric NAME ...``, checked like a
    study file (StudyError)."""
    problems = []
    if not sets:
        problems.append("perga sweep CASE: give at least one --set KEY=V1,V2 (or KEY=LO:HI:N)")
    if not metrics:
        problems.append(f"perga sweep CASE: give at least one --metric NAME; {metric_names()}")
    parameters = {}
    for text in sets:
        key, sep, values = text.partition("=")
        if not sep or not key.strip() or not values.strip():
            problems.append(f"--set {text!r}: expected KEY=V1,V2,... or KEY=LO:HI:N")
            continue
        try:
            shown = text if len(text) <= 80 else f"{text[:77]}..."
            parameters[key.strip()] = parse_values(values, f"--set {shown}")
        except StudyError as exc:
            problems += exc.problems
    problems += check_metrics(metrics, "--metric")
    if parameters:
        problems += check_parameters(case, parameters, "--set")
    if problems:
        raise StudyError(problems)
    return Study(
        case=case.resolve(),
        parameters=parameters,
        metrics=metrics,
        replicates=replicates,
        seed=seed,
    )


def metric_names() -> str:
    """The metric names, for messages."""
    return "metrics: " + ", ".join(METRICS)
