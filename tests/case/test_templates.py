"""perga new: every template is written with its geometry beside it into an empty folder, and
runs from there; refusals name what is in the way; every key of a template carries a comment
naming its unit, as the schema gives it, and its meaning."""

import json
import re
import tomllib
import typing
from collections.abc import Iterator

import pytest
from pydantic import BaseModel

from perga.case.reference import choices, field_unit, tables_of
from perga.case.schema import Case
from perga.case.templates import CASES, TEMPLATES
from perga.cli import main


@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_a_new_case_runs_from_an_empty_folder(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["new", name, "-o", "x.toml"]) == 0
    assert main(["run", "x.toml", "--quiet", "--set", "solver.duration=0.004"]) == 0
    summary = json.loads((tmp_path / "runs" / "x" / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "completed"
    assert (
        (tmp_path / "x.toml")
        .read_text(encoding="utf-8")
        .startswith(f"# A perga case made by `perga new {name}`")
    )


def test_refusals_name_the_file_or_the_templates(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["new", "-o", "x.toml"]) == 0  # the default template: separator
    assert main(["new", "-o", "x.toml"]) == 2
    assert "x.toml exists (--overwrite replaces it)" in capsys.readouterr().err
    assert main(["new", "-o", "x.toml", "--overwrite"]) == 0
    assert main(["new", "fed", "-o", "y.toml"]) == 2
    assert "no template 'fed'; there are: single-impact" in capsys.readouterr().err
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "chamber_screen.svg").write_text("mine")
    assert main(["new", "fed-separator", "-o", "z.toml"]) == 2  # a geometry file in the way
    assert (tmp_path / "geometry" / "chamber_screen.svg").read_text() == "mine"
    assert not (tmp_path / "z.toml").exists()


def test_beside_the_same_geometry_file_it_is_kept(tmp_path, monkeypatch, capsys):
    """The README's tour from the repository root: geometry/chamber_screen.svg there holds the
    template's bytes, so the case is written and the file kept, with and without --overwrite
    (in an editable install the file is the template's own); a different file is refused with
    the remedy and nothing is written."""
    root = CASES.parent
    monkeypatch.chdir(root)
    before = (root / "geometry" / "chamber_screen.svg").read_bytes()
    mine = root / f"tour-{tmp_path.name}.toml"
    try:
        for extra in ([], ["--overwrite"]):
            assert main(["new", "fed-separator", "-o", mine.name, *extra]) == 0
            assert (root / "geometry" / "chamber_screen.svg").read_bytes() == before
    finally:
        mine.unlink(missing_ok=True)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "chamber_screen.svg").write_bytes(before)
    assert main(["new", "fed-separator", "-o", "same.toml"]) == 0
    assert "wrote same.toml; next" in capsys.readouterr().out
    (tmp_path / "geometry" / "chamber_screen.svg").write_bytes(before + b"<!-- mine -->")
    assert main(["new", "fed-separator", "-o", "other.toml"]) == 2
    assert "differs from the template's chamber_screen.svg: write the case into another folder" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "other.toml").exists()


KEY_LINE = re.compile(r"^(?P<key>[A-Za-z_][\w-]*) = ")
HEADER = re.compile(r"^\[\[?(?P<table>[\w.-]+)\]\]?\s*$")


def _every_field() -> list[tuple[type[BaseModel], str]]:
    """(table, key) of every key of the schema."""
    found, todo = [], [Case]
    while todo:
        model = todo.pop()
        for name, field in model.model_fields.items():
            found.append((model, name))
            todo += [m for m in tables_of(field.annotation) if m not in {f[0] for f in found}]
    return found


UNITS = {u for model, name in _every_field() for u in field_unit(model, name)}
"""Every unit the schema gives a key, "-" (dimensionless) included."""


def _table_model(path: tuple[str, ...]) -> type[BaseModel]:
    """The schema table of a [header] (``materials.beebread``: Material)."""
    model, names = Case, list(path)
    while names:
        field = model.model_fields[names.pop(0)]
        if typing.get_origin(field.annotation) is dict:
            names.pop(0)  # the entry's own name
        (model,) = tables_of(field.annotation)
    return model


def _split(chunk: str) -> tuple[dict, str | None] | None:
    """The TOML data of key line(s) ``chunk`` and their trailing comment, None if the value
    runs on past ``chunk`` (a multi-line string)."""
    last = chunk.rfind("\n") + 1
    for at in (i for i, c in enumerate(chunk) if c == "#" and i >= last):
        try:
            return tomllib.loads(chunk[:at]), chunk[at + 1 :].strip()
        except tomllib.TOMLDecodeError:
            continue
    try:
        return tomllib.loads(chunk), None
    except tomllib.TOMLDecodeError:
        return None


def key_lines(text: str) -> Iterator[tuple[tuple[str, ...], str, object, str | None, int]]:
    """(table path, key, value, trailing comment, line number) of every key line of a TOML
    text (a multi-line value's comment on its last line)."""
    lines, table, i = text.splitlines(), (), 0
    while i < len(lines):
        if header := HEADER.match(lines[i]):
            table = tuple(header["table"].split("."))
        elif key := KEY_LINE.match(lines[i]):
            j = next(j for j in range(i, len(lines)) if _split("\n".join(lines[i : j + 1])))
            data, comment = _split("\n".join(lines[i : j + 1]))
            yield table, key["key"], data[key["key"]], comment, i + 1
            i = j
        i += 1


def expected(table: tuple[str, ...], key: str, value: object) -> tuple[set[str], set[str]]:
    """The units a key line's comment names (its inline table's keys' too) and the values of
    its choices (an inline table's: the kinds of every form the key takes)."""
    model = _table_model(table)
    field = model.model_fields[key]
    if not isinstance(value, dict):
        return set(field_unit(model, key)), set(choices(field))
    forms = tables_of(field.annotation)
    kinds = {k for m in forms if "kind" in m.model_fields for k in choices(m.model_fields["kind"])}
    (form,) = [
        m for m in forms if len(forms) == 1 or value["kind"] in choices(m.model_fields["kind"])
    ]
    units = {u for name in value for u in field_unit(form, name)}
    values = {v for name in value if name != "kind" for v in choices(form.model_fields[name])}
    return units, kinds | values


@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_every_key_of_a_template_is_commented_with_its_unit(name):
    """Every key line of every template ends in a comment "# UNITS: meaning" whose UNITS are
    exactly the units the schema gives its keys (an inline table's: all of them; "-" for a
    dimensionless number), or that has no units where its keys are not numbers, and that
    names every value a choice among its keys takes, quoted."""
    text = (CASES / TEMPLATES[name][0]).read_text(encoding="utf-8")
    for table, key, value, comment, line in key_lines(text):
        where = f"{TEMPLATES[name][0]}:{line} ({key})"
        assert comment, f"{where}: no comment"
        head, _, meaning = comment.partition(": ")
        named = set(head.split(", "))
        if not named <= UNITS:
            named, meaning = set(), comment
        units, values = expected(table, key, value)
        assert named == units, f"{where}: the comment names {named or 'no unit'}, not {units}"
        assert meaning.strip(), f"{where}: the comment has no meaning after its unit"
        missing = [v for v in values if f'"{v}"' not in comment]
        assert not missing, f"{where}: the comment does not name {missing}"
