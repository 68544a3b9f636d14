"""Run parameters declared as dataclass fields: type from the annotation, checks that name the
parameter, its range and unit, and the help text and flags made from them."""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import pytest

from tightknot.loading.options import (
    LoadPath,
    Range,
    flag,
    flag_kwargs,
    on_off,
    param,
    parameters,
)


@dataclass(frozen=True)
class _Toy:
    name: str = param(valid=("a", "b"), what="which one", aliases={"A": "a"})
    size: float = param(2.0, Range(0.0, 10.0, low_open=True), "m", "how long")
    count: int | None = param(None, Range(1, 5), "", "how many", only="open",
                              default_text="3 open")
    flag_on: bool = param(True, None, "", "switch")


def test_the_annotation_gives_type_and_nullability() -> None:
    p = parameters(_Toy)
    assert list(p) == ["name", "size", "count", "flag_on"]
    assert (p["name"].kind, p["name"].required) == (str, True)
    assert (p["size"].kind, p["size"].nullable, p["size"].default) == (float, False, 2.0)
    assert (p["count"].kind, p["count"].nullable) == (int, True)
    assert p["flag_on"].kind is bool


@pytest.mark.parametrize(("key", "value", "words"), [
    ("size", 0.0, "size: 0.0 is out of range; valid: (0, 10] m (how long)"),
    ("size", float("inf"), "size: inf is out of range"),
    ("size", "1", "size: expected a number m (how long), got '1'"),
    ("size", True, "expected a number"),
    ("size", None, "size: must not be null (how long)"),
    ("count", 2.0, "count: expected an integer (open: how many), got 2.0"),
    ("count", 9, "count: 9 is out of range; valid: [1, 5] (open: how many)"),
    ("name", "c", "name: 'c' is not one of: a, b, A (which one)"),
    ("name", 1, "name: expected a string"),
    ("flag_on", 1, "flag_on: expected true or false (switch), got 1"),
])
def test_a_bad_value_names_the_parameter_and_its_range(key: str, value, words: str) -> None:
    with pytest.raises(ValueError) as err:
        parameters(_Toy)[key].check(value)
    assert words in str(err.value)


def test_a_good_value_is_normalised() -> None:
    p = parameters(_Toy)
    assert p["size"].check(3) == 3.0 and isinstance(p["size"].check(3), float)
    assert p["count"].check(None) is None
    assert p["name"].check("A") == "a"
    assert p["size"].check(1.5, "size[2]") == 1.5
    with pytest.raises(ValueError, match=r"size\[2\]: -1.0 is out of range"):
        p["size"].check(-1, "size[2]")


def test_help_and_flags_come_from_the_declaration() -> None:
    p = parameters(_Toy)
    assert p["size"].help_text() == "how long [m] in (0, 10] (default 2)"
    assert p["count"].help_text() == "open: how many in [1, 5] (default 3 open)"
    assert flag("lambda_tolerance") == "--lambda-tolerance"
    parser = argparse.ArgumentParser()
    for name, par in p.items():
        parser.add_argument(flag(name), **flag_kwargs(par, nargs="+" if name == "size" else None))
    args = parser.parse_args(["--name", "A", "--size", "1", "2", "--flag-on", "off"])
    assert (args.name, args.size, args.count, args.flag_on) == ("A", [1.0, 2.0], None, False)
    with pytest.raises(argparse.ArgumentTypeError, match="on or off"):
        on_off("yes")


def test_the_load_path_defaults_are_class_attributes() -> None:
    # So that a function can write tighten_steps: int = LoadPath.tighten_steps.
    assert (LoadPath.tighten_steps, LoadPath.pull_steps, LoadPath.residual_tol,
            LoadPath.relax_iterations, LoadPath.lambda_tolerance) == (40, 10, 1e-6, 2000, 0.1)
    assert LoadPath() == LoadPath(force=None)
