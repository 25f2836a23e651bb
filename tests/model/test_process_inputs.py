"""Bad process inputs (sizes, feed, outlet, damage) are refused with exit 2 and a message naming
the key; each refusal is tried on both sides of its limit, on the bundled separator case."""

from __future__ import annotations

from pathlib import Path

import pytest

from perga.cli import main
from tests.case_text import case_text

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = case_text(ROOT / "cases" / "bee-bread-separator.toml")


def _validate(tmp_path: Path, text: str, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    case = tmp_path / "case.toml"
    case.write_text(text.replace("../geometry", str(ROOT / "geometry")))
    code = main(["validate", str(case)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err


def _with(old: str, new: str) -> str:
    assert old in BUNDLED, old
    return BUNDLED.replace(old, new)


SIZE = 'size = { kind = "uniform", low = 0.00245, high = 0.00265 }'


@pytest.mark.parametrize(
    ("fractions", "ok"),
    [("[0.25, 0.75]", True), ("[0.25, 0.7500000001]", True), ("[0.25, 0.76]", False),
     ("[0.25, 0.74]", False), ("[-0.25, 1.25]", False)],
)  # fmt: skip
def test_size_table_fractions_must_sum_to_one(tmp_path, capsys, fractions, ok):
    table = f'size = {{ kind = "table", radii = [0.0025, 0.0026], fractions = {fractions} }}'
    code, err = _validate(tmp_path, _with(SIZE, table), capsys)
    assert code == (0 if ok else 2), err
    if not ok:
        assert "granules.size" in err and "sum to 1" in err


@pytest.mark.parametrize(("centre", "ok"), [("[0.1485, 0.1485]", True), ("[0.24, 0.2]", False)])
def test_feed_region_must_be_inside_the_chamber(tmp_path, capsys, centre, ok):
    """The region's corner at 0.1485·√2 + 0.007 = 0.217 m is inside the 0.3 m wall; moved to
    (0.24, 0.2) a corner is at 0.31 m, outside."""
    old = "region = { centre = [0.1485, 0.1485], size = [0.01, 0.01], angle = 2.356 }"
    new = f"region = {{ centre = {centre}, size = [0.01, 0.01], angle = 2.356 }}"
    code, err = _validate(tmp_path, _with(old, new), capsys)
    assert code == (0 if ok else 2), err
    if not ok:
        assert "feed.region" in err and "outside the chamber" in err


@pytest.mark.parametrize(
    ("point", "ok"), [("[0.0, -0.38]", True), ("[0.0, -0.5]", False), ("[0.3, -0.38]", False)]
)
def test_screen_must_cut_the_wall(tmp_path, capsys, point, ok):
    """The bundled screen closes the outlet channel at y = −0.38 m; a line at −0.5 m is beyond
    the wall, and one 0.3 m aside with its 0.15 m width misses the 0.15 m wide channel."""
    code, err = _validate(tmp_path, _with("point = [0.0, -0.38]", f"point = {point}"), capsys)
    assert code == (0 if ok else 2), err
    if not ok:
        assert "outlet" in err and "does not cut the chamber's wall" in err


def test_damage_needs_the_materials_breakage(tmp_path, capsys):
    text = _with("breakage = { f_mat = 0.1, w_min = 30.0 }\n", "")
    code, err = _validate(tmp_path, text, capsys)
    assert code == 2 and "damage: needs [materials.beebread.breakage]" in err
    code, err = _validate(tmp_path, text.replace('[damage]\naction = "mark"\n', ""), capsys)
    assert code == 0, err


def test_hertz_takes_several_sizes_of_one_material(tmp_path, capsys):
    """Hertz stiffness k_n√R* takes R* from each contact's radii in the kernel
    (tests/model/test_materials.py), so a size distribution is a valid Hertz case (it was
    refused while R* was tabled per material pair)."""
    hertz = _with(
        'kind = "linear"\nduration = 1e-4', 'kind = "hertz"\nstiffness = 1e9\nduration = 1e-4'
    ).replace("duration = 1e-4\n", "")
    code, err = _validate(tmp_path, hertz, capsys)
    assert code == 0, err
    code, err = _validate(tmp_path, hertz.replace(SIZE + "\n", ""), capsys)
    assert code == 0, err
