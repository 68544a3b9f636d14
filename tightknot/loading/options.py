"""Run parameters declared once, and the options of the load path that ties a knot.

A run parameter is a dataclass field made by :func:`param`: its default is the field's, and
its metadata (a :class:`Param`) carries the valid range or values, the SI unit and what it
means. From these the config loader checks its keys (:meth:`Param.check`), the command line
makes its flags (:func:`flag_kwargs`) and the sweep fills in and checks its cases, so a
default, a range or a help text is written in one place only.

:class:`LoadPath` holds the load path's parameters (how a knot is tightened and pulled); the
scene's and the outputs' live in :mod:`tightknot.study.params`.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, field
from typing import Any


@dataclass(frozen=True)
class Range:
    """Valid interval of a number; ``low_open``/``high_open`` exclude the end points."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def contains(self, v: float) -> bool:
        above = v > self.low if self.low_open else v >= self.low
        below = v < self.high if self.high_open else v <= self.high
        return math.isfinite(v) and above and below

    def text(self) -> str:
        return (f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                f"{')' if self.high_open else ']'}")


@dataclass(frozen=True)
class Param:
    """One run parameter: its valid values, unit and meaning.

    :func:`param` sets what is written beside the field; :func:`parameters` fills in
    ``name``, ``kind``, ``nullable``, ``default`` and ``required`` from the dataclass field.

    Attributes:
        name: the field's name (config key, sweep parameter, flag ``--name-with-dashes``).
        kind: float, int, str or bool (from the field's annotation).
        nullable: None is a value (the annotation says ``| None``): not used, or resolved
            later (e.g. per knot).
        default: the field's default.
        required: the field has no default (it must be given).
        valid: a :class:`Range` for numbers, the allowed values (tuple), or None (any).
        unit: SI unit ("" for a pure number).
        what: what it is, one phrase (in error messages and in ``--help``).
        only: "closed" or "open" when it applies to one kind of knot only.
        default_text: the default as ``--help`` states it when the field's default is None
            and resolved later (e.g. "200 closed; 300 open").
        aliases: other spellings of allowed strings, alias -> name.
        metavar: placeholder of its value on the command line.
        flag_aliases: other flags of the same option (e.g. ``--knot`` for ``--knot-type``).
    """

    name: str = ""
    kind: type = object
    nullable: bool = False
    default: Any = None
    required: bool = False
    valid: Range | tuple[Any, ...] | None = None
    unit: str = ""
    what: str = ""
    only: str | None = None
    default_text: str = ""
    aliases: Mapping[str, str] = field(default_factory=dict)
    metavar: str | None = None
    flag_aliases: tuple[str, ...] = ()

    @property
    def meaning(self) -> str:
        """``what``, prefixed with the knot it applies to (e.g. "open: final pulling force")."""
        return f"{self.only}: {self.what}" if self.only else self.what

    def check(self, value: Any, name: str | None = None) -> Any:
        """``value`` checked against type and range, normalised (an int where a float is due
        becomes a float, an alias its name); ValueError naming the parameter (or ``name``),
        its valid range and unit otherwise."""
        key, what = name or self.name, self.meaning
        u = f" {self.unit}" if self.unit else ""
        if value is None:
            if self.nullable:
                return None
            raise ValueError(f"{key}: must not be null ({what})")
        if self.kind is float:
            # bool is an int in Python; true/false is never a number here.
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{key}: expected a number{u} ({what}), got {value!r}")
            value = float(value)
        elif self.kind is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ValueError(f"{key}: expected an integer ({what}), got {value!r}")
        elif self.kind is bool:
            if not isinstance(value, bool):
                raise ValueError(f"{key}: expected true or false ({what}), got {value!r}")
        elif not isinstance(value, str):
            raise ValueError(f"{key}: expected a string ({what}), got {value!r}")
        if isinstance(value, str):
            value = self.aliases.get(value, value)
        if isinstance(self.valid, Range) and not self.valid.contains(float(value)):
            raise ValueError(f"{key}: {value!r} is out of range; valid: {self.valid.text()}{u} "
                             f"({what})")
        if isinstance(self.valid, tuple) and value not in self.valid:
            names = ", ".join(map(str, self.valid + tuple(self.aliases)))
            raise ValueError(f"{key}: {value!r} is not one of: {names} ({what})")
        return value

    def default_str(self) -> str:
        """The default as the command line spells it ("" when there is none)."""
        if self.default_text:
            return self.default_text
        if self.required or self.default is None:
            return ""
        return format_value(self.default)

    def help_text(self, meaning: str | None = None) -> str:
        """``--help`` text: meaning (``meaning`` replaces it), unit, valid range, default."""
        text = (meaning or self.meaning) + (f" [{self.unit}]" if self.unit else "")
        if isinstance(self.valid, Range):
            text += f" in {self.valid.text()}"
        elif isinstance(self.valid, tuple) and self.metavar is not None:
            # A metavar hides argparse's list of choices: the help lists them.
            text += ": " + ", ".join(map(str, self.valid))
            text += "".join(f"; {a} = {n}" for a, n in self.aliases.items())
        default = self.default_str()
        if default:
            text += f" (default {default})"
        return text


def format_value(value: Any) -> str:
    """A parameter value as the command line spells it: 0.0085, 1.25e+06, on/off."""
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def param(default: Any = MISSING, valid: Range | tuple[Any, ...] | None = None,
          unit: str = "", what: str = "", *, only: str | None = None, default_text: str = "",
          aliases: Mapping[str, str] | None = None, metavar: str | None = None,
          flag_aliases: tuple[str, ...] = ()) -> Any:
    """A dataclass field that is a run parameter (arguments: :class:`Param`'s attributes)."""
    meta = Param(valid=valid, unit=unit, what=what, only=only, default_text=default_text,
                 aliases=dict(aliases or {}), metavar=metavar, flag_aliases=flag_aliases)
    return field(default=default, metadata={"param": meta})


def _kind(hint: Any) -> tuple[type, bool]:
    """(kind, nullable) of an annotation such as ``float`` or ``int | None``."""
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        if len(args) != 1:
            raise TypeError(f"a run parameter has one type (or it | None), got {hint}")
        return args[0], True
    return hint, False


@functools.cache
def parameters(cls: type) -> Mapping[str, Param]:
    """The run parameters of dataclass ``cls`` (its :func:`param` fields), in field order."""
    hints = typing.get_type_hints(cls)
    out: dict[str, Param] = {}
    for f in dataclasses.fields(cls):
        meta = f.metadata.get("param")
        if meta is None:
            continue
        kind, nullable = _kind(hints[f.name])
        required = f.default is MISSING
        out[f.name] = dataclasses.replace(meta, name=f.name, kind=kind, nullable=nullable,
                                          default=None if required else f.default,
                                          required=required)
    return types.MappingProxyType(out)


def flag(name: str) -> str:
    """The command-line flag of parameter ``name`` (``--name-with-dashes``)."""
    return "--" + name.replace("_", "-")


def flags(p: Param) -> tuple[str, ...]:
    """Every command-line flag of parameter ``p``: :func:`flag` of its name first (argparse
    takes the option's name from it), then its ``flag_aliases``."""
    return (flag(p.name), *p.flag_aliases)


def on_off(text: str) -> bool:
    """argparse type of a yes/no flag: "on" or "off"."""
    if text not in ("on", "off"):
        raise argparse.ArgumentTypeError(f"expected on or off, got {text!r}")
    return text == "on"


def flag_kwargs(p: Param, nargs: str | None = None, what: str | None = None,
                note: str = "") -> dict[str, Any]:
    """Keyword arguments of ``argparse.add_argument`` for parameter ``p``: type, choices,
    metavar and help (``what`` replaces its meaning there, ``note`` follows it);
    ``nargs="+"`` for a list. The default is None, so that a caller can tell a flag that
    was not given."""
    kw: dict[str, Any] = {"default": None}
    if p.kind is bool:
        kw.update(type=on_off, metavar="{on,off}")
    elif isinstance(p.valid, tuple):
        kw["choices"] = list(p.valid) + list(p.aliases)
    else:
        kw["type"] = p.kind
    if p.metavar is not None:
        kw["metavar"] = p.metavar
    if nargs is not None:
        kw["nargs"] = nargs
    text = p.help_text(what) + note
    # argparse formats help with %: a literal one is doubled.
    kw["help"] = text.replace("%", "%%")
    return kw


#: The coarse vertex count of the mesh continuation a run of a long rod takes by default:
#: the relaxation of a loose start costs one to a few Newton iterations per vertex, and a
#: rod of more than one and a half times this many ties faster, and within the
#: relaxation's budget, coarse first (the 1 m rod at 600 vertices relaxed in 2006
#: iterations, past the budget of 2000; from 300 it ties in 992).
REFINE_FROM = 300


def default_coarse_nodes(nodes: int) -> int | None:
    """The coarse vertex count a rod of ``nodes`` vertices ties on first by default
    (:data:`REFINE_FROM` above 1.5 times that many, else None: no mesh continuation)."""
    return REFINE_FROM if 2 * nodes > 3 * REFINE_FROM else None

#: How a sectioned scene's load path runs (:func:`tightknot.loading.tie.path_scene`).
SECTION_PATHS = ("auto", "final", "full", "pull")


@dataclass(frozen=True)
class LoadPath:
    """The load path that ties a knot (SI units): tighten (the rest length shrinks to L0),
    then, for an open knot, pull by ``force``, to ``end_distance`` or to ``target_lambda``.

    The defaults are those of ``tightknot tie`` and of a sweep case. ``tighten_steps``,
    ``pull_steps`` and ``relax_iterations`` drive :func:`tightknot.loading.tie.tie`;
    a pull to ``target_lambda`` (:func:`tightknot.loading.pull.tie_to_lambda`) searches the
    force with ``lambda_tolerance`` and ``residual_tol``. Class attributes are the defaults
    (``LoadPath.tighten_steps == 40``), so that a function can take its defaults from here.
    """

    force: float | None = param(None, Range(0.0, 1e6, low_open=True), "N",
                                "final pulling force", only="open", metavar="F")
    end_distance: float | None = param(None, Range(0.0, 100.0, low_open=True), "m",
                                       "final end-to-end distance", only="open")
    target_lambda: float | None = param(None, Range(0.0, 1e3, True, True), "",
                                        "pull until Lambda_OC reaches this", only="open",
                                        metavar="LAMBDA")
    lambda_tolerance: float = param(0.1, Range(0.0, 1e3, True, True), "",
                                    "how close a target Lambda_OC is reached", only="open")
    tighten_steps: int = param(40, Range(1, 100_000), "", "initial load steps of the tightening")
    pull_steps: int = param(10, Range(1, 100_000), "", "initial load steps of the pull")
    residual_tol: float = param(1e-6, Range(0.0, 1.0, True, True), "",
                                "Newton tolerance on the scaled residual")
    relax_iterations: int = param(2000, Range(1, 1_000_000), "",
                                  "Newton budget of the start curve's relaxation")
    coarse_nodes: int | None = param(None, Range(24, 200_000), "",
                                     "mesh continuation: tie at this many vertices first "
                                     "(at least as many as keep the start's edges within "
                                     "pi/4 D0), then refine by doubling "
                                     "(tightknot.loading.refine)",
                                     default_text=f"{REFINE_FROM} for a rod of more than "
                                     f"{3 * REFINE_FROM // 2} vertices, else off", metavar="N")
    section_path: str = param("auto", SECTION_PATHS, "",
                              "the sectioned level's load path: final (relax, tighten and "
                              "pull at the compliant level, the sections' equilibrium solved "
                              "under the final load; an open knot's target Lambda_OC sought "
                              "again there), full (every load step with the sections: a "
                              "pulled knot's equilibrium can depend on its path), pull "
                              "(relax and tighten at the compliant level, then the sections "
                              "added and the knot pulled with them) or auto (final for a "
                              "closed knot and for an open one whose pull loosens it, pull "
                              "for an open knot pulled tighter)")
    # A setting of the sectioned level beside its path, not a scene parameter: sweeps run
    # without it, so their case ids stay (tightknot/sweep/cases.py, NOT_CASE_KEYS).
    section_bend_shift: bool = param(False, None, "",
                                     "at the sectioned contact level, move each section "
                                     "toward its bend's centre by nu kappa R^2 / 2 "
                                     "(Saint-Venant's anticlastic shift; off by default: "
                                     "docs/sectioned_level.md)")
    section_thinning: str = param("edge", ("edge", "rod"), "",
                                  "at the sectioned contact level, the stretch that thins "
                                  "the sections: each edge's own (edge) or the rod's mean "
                                  "L/L0 (rod: no axial pull of the contact on the edges it "
                                  "presses; docs/sectioned_level.md, 'Resolution')")


#: The loads of an open knot's pull: a run gives exactly one of them.
LOADS = ("force", "end_distance", "target_lambda")
