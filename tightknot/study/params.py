"""The parameters of a knot run, declared once: the scene, the load path and the outputs.

:class:`Scene` (which knot, its rod and its contact model), :class:`tightknot.loading.options.
LoadPath` (how it is tied) and :class:`Output` (what the run writes) each list their fields
with default, valid range, unit and meaning (:func:`tightknot.loading.options.param`). The
``tightknot tie`` config and flags (:mod:`tightknot.app.config`) and the sweep's cases and
flags (:mod:`tightknot.sweep.cases`, :mod:`tightknot.sweep.commands`) are generated from them.

Defaults that depend on the knot (its length, vertex count and twist) are the table
:data:`KNOT_DEFAULTS`; a field whose default is None there is resolved from it per knot.
SI units throughout.
"""

from __future__ import annotations

import types
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from tightknot.knots.catalogue import KNOT_NAMES
from tightknot.knots.scenes import (
    DEFAULT_EDGE_D0,
    START_SHAPES,
    default_l0_over_d0,
    default_nodes,
    default_open_length,
)
from tightknot.loading.options import LoadPath, Range, format_value, param, parameters
from tightknot.viz.rerun_log import ROD_FIELDS

if TYPE_CHECKING:
    from tightknot.knots.scenes import KnotScene

KNOTS = ("closed", "open")
#: Knot types with a scene (the built-in knots, tightknot.knots.catalogue), and the scene's
#: name of each (closed_trefoil, open_5_2, ...).
KNOT_TYPES = KNOT_NAMES
SCENE_NAMES = {t: {"3_1": "trefoil", "4_1": "figure_eight"}.get(t, t) for t in KNOT_TYPES}
#: Contact levels that can tie a knot (tightknot.knots.scenes.CONTACT_LEVELS less "off").
CONTACT_LEVELS = ("compliant", "smoothed", "sectioned", "rigid")

#: Defaults that depend on the knot, (knot, knot_type) -> {key: value} (the vertex count
#: follows the rest length: :func:`resolve_nodes`): the scenes' own
#: (:func:`tightknot.knots.scenes.default_l0_over_d0`, :func:`~tightknot.knots.scenes.
#: default_open_length`: the study's trefoils, L0/D0 = 16.37 and L0 = 185 mm; the others
#: from their ideal L/D); twist off for open knots (an isotropic rod with twist-free ends
#: relaxes its twist to zero).
KNOT_DEFAULTS: Mapping[tuple[str, str], Mapping[str, Any]] = types.MappingProxyType({
    **{("closed", t): {"l0_over_d0": default_l0_over_d0(t), "twist": True}
       for t in KNOT_TYPES},
    **{("open", t): {"length": default_open_length(t), "twist": False} for t in KNOT_TYPES},
})
#: Fewest vertices of a knot's scene (tightknot.knots.scenes refuses fewer).
MIN_NODES = {"closed": 24, "open": 40}

#: Fields a rod tube may be coloured by in the .rrd (the logger's).
COLOR_FIELDS = tuple(ROD_FIELDS)
#: Short aliases accepted for ``color_by`` (the CLI's spelling of the issue's field names).
COLOR_ALIASES = {"contact_width": "contact_width_fraction"}


def _knot_default_text(key: str, shown: int = 2) -> str:
    """``--help``'s default of a per-knot parameter, from :data:`KNOT_DEFAULTS`, for the
    first ``shown`` knot types (e.g. "on closed, off open"; "16.37 for 3_1, 22.1 for 4_1,
    per knot for the others")."""
    per_knot = {knot: {t: KNOT_DEFAULTS[(knot, t)][key] for t in KNOT_TYPES
                       if key in KNOT_DEFAULTS[(knot, t)]} for knot in KNOTS}
    if any(len(set(v.values())) > 1 for v in per_knot.values()):
        per_knot = {knot: dict(list(v.items())[:shown]) for knot, v in per_knot.items()}
        return _join_defaults(per_knot) + ", per knot for the others (tightknot.knots.scenes)"
    return _join_defaults(per_knot)


def _join_defaults(per_knot: dict[str, dict[str, Any]]) -> str:
    """knot -> {knot type: default} as ``--help`` writes it."""
    per_knot = {knot: v for knot, v in per_knot.items() if v}
    parts = []
    for knot, values in per_knot.items():
        where = f" {knot}" if len(per_knot) > 1 else ""
        if len(set(values.values())) == 1:
            parts.append(f"{format_value(next(iter(values.values())))}{where}")
        else:
            parts += [f"{format_value(v)}{where} for {t}" for t, v in values.items()]
    return ", ".join(parts)


# Ranges bound what the model can mean physically or what the machine can hold, not what
# the study used: a run outside the study is allowed, a negative length or a 10^9-vertex
# rod is not.
@dataclass(frozen=True)
class Scene:
    """The knot scene of a run (SI units): which knot, its rod and its contact model
    (tightknot.knots.scenes: what each contact level and ``twist`` neglect)."""

    knot: str = param(valid=KNOTS, what="closed or open knot")
    knot_type: str = param("3_1", KNOT_TYPES, "",
                           "knot type, its name in the knot table (3_1 the study's trefoil, "
                           "4_1 figure-eight, torus and twist knots: tightknot.knots."
                           "catalogue)", flag_aliases=("--knot",), metavar="KNOT")
    l0_over_d0: float | None = param(None, Range(10.0, 1e4), "",
                                     "rest length over diameter L0/D0", only="closed",
                                     default_text=_knot_default_text("l0_over_d0"),
                                     metavar="R")
    length: float | None = param(None, Range(0.0, 100.0, low_open=True), "m",
                                 "rest length L0", only="open",
                                 default_text=_knot_default_text("length"), metavar="L0")
    nodes: int | None = param(None, Range(24, 200_000), "", "vertices of the rod",
                              default_text=f"one per {DEFAULT_EDGE_D0:g} D0 of rest length")
    diameter: float = param(8.5e-3, Range(0.0, 1.0, low_open=True), "m", "rest diameter D0",
                            metavar="D0")
    youngs_modulus: float = param(1.25e6, Range(0.0, 1e12, low_open=True), "Pa",
                                  "Young's modulus E", metavar="E")
    poisson: float = param(0.5, Range(-1.0, 0.5, low_open=True), "", "Poisson ratio nu",
                           metavar="NU")
    # Statics does not depend on the density; only the proximal steps that carry a solve
    # through a limit point do.
    density: float = param(1160.0, Range(0.0, 1e5), "kg/m^3", "mass density", metavar="RHO")
    contact: str = param("compliant", CONTACT_LEVELS, "",
                         "contact level: compliant (the FEM-calibrated law), smoothed "
                         "(sections thinned by the stretch averaged over +-1 D0), sectioned "
                         "(each section's Fourier modes as state, contact between the "
                         "deformed boundaries), rigid (a rigid tube)")
    section_modes: int = param(8, Range(4, 12), "",
                               "highest Fourier mode N of each section at the sectioned "
                               "contact level (an ellipse cannot wrap a convex partner: "
                               ">= 4)", metavar="N")
    twist: bool | None = param(None, None, "", "twist dofs",
                               default_text=_knot_default_text("twist"))
    grip_length: float = param(1.0, Range(0.0, 1e3), "D0",
                               "length of each tail held on the pull axis by a grip "
                               "(0: hinged ends)", only="open", metavar="LG")
    grip_twist: str = param("free", ("free", "clamped"), "",
                            "the rod in a grip: free to spin about the pull axis, or "
                            "clamped (with twist dofs)", only="open")


@dataclass(frozen=True)
class StartFile:
    """The user's own start curve of a ``tie`` run (:mod:`tightknot.knots.start_curve`): a
    centerline file read as ``tightknot analyze`` reads it, closed or open as the run's knot
    says. Its knot type is detected (``knot_type`` must match it when given)."""

    start: str | None = param(None, None, "", "start curve: a centerline file (the reader of "
                              "tightknot analyze), tied from its own shape and length; its "
                              "knot type is detected and kept", metavar="FILE")
    units: str | None = param(None, None, "", "unit of the start file's coordinates: m, cm, "
                              "mm, um or metres per file unit (the run's own lengths stay SI)",
                              default_text="the header's unit, else m", metavar="UNIT")
    columns: str | None = param(None, None, "", "the start file's x,y,z columns: 1-based "
                                "numbers (2,3,4) or header names",
                                default_text="as tightknot analyze picks them",
                                metavar="X,Y,Z")
    start_shape: str = param("parametric", START_SHAPES, "",
                             "start of a built-in closed knot: its family's parametric curve, "
                             "or the shipped ideal polygon (3_1, 4_1, 5_1, 6_1, 8_19; "
                             "tightknot.knots.ideal)", only="closed")


@dataclass(frozen=True)
class Output:
    """What a run writes besides its numbers, and where it runs."""

    color_by: str = param("kappa_D0", COLOR_FIELDS, "", "field colouring the rod tube in the "
                          ".rrd", aliases=COLOR_ALIASES, metavar="FIELD")
    device: str | None = param(None, None, "", "Warp device, e.g. cpu or cuda:0",
                               default_text="cpu")


#: Every run parameter by name: the scene's, the start curve's, the load path's and the
#: outputs'.
RUN_PARAMS = types.MappingProxyType({**parameters(Scene), **parameters(StartFile),
                                     **parameters(LoadPath), **parameters(Output)})


def knot_defaults(knot: str, knot_type: str = "3_1") -> dict[str, Any]:
    """The defaults of ``knot`` ("closed"/"open") of ``knot_type`` that depend on it."""
    return dict(KNOT_DEFAULTS[(knot, knot_type)])


def resolve_nodes(values: Mapping[str, Any]) -> int:
    """The vertex count of a scene whose ``nodes`` is not given: from its rest length
    (:func:`tightknot.knots.scenes.default_nodes`; ``values``: the resolved scene)."""
    closed = values["knot"] == "closed"
    length_over_d0 = (values["l0_over_d0"] if closed
                      else values["length"] / values.get("diameter", Scene.diameter))
    return default_nodes(length_over_d0, closed)


def check_scene(values: Mapping[str, Any]) -> None:
    """The rules between a scene's checked parameters (``values``: the knot and what is
    given): the fewest vertices of the knot, the tails of an open knot. ValueError naming
    the parameter."""
    knot = values["knot"]
    nodes = values.get("nodes")
    if nodes is not None and nodes < MIN_NODES[knot]:
        p = RUN_PARAMS["nodes"]
        raise ValueError(f"nodes: {nodes!r} is out of range for {knot} knots; valid: "
                         f"[{MIN_NODES[knot]}, {p.valid.high:g}] ({p.meaning})")
    shape = values.get("start_shape", StartFile.start_shape)
    if shape != "parametric":
        from tightknot.knots.ideal import IDEAL_KNOTS

        kt = values.get("knot_type", Scene.knot_type)
        if knot != "closed" or values.get("start") is not None or kt not in IDEAL_KNOTS:
            raise ValueError(f"start_shape {shape}: for a closed built-in knot whose ideal "
                             f"shape is shipped ({', '.join(IDEAL_KNOTS)}), without start")
    length = values.get("length")
    if knot == "open" and length is not None:
        d0 = values.get("diameter", Scene.diameter)
        if length < 10.0 * d0:
            raise ValueError(f"length must be >= 10 D0 = {10 * d0:.4g} m for an open knot, got "
                             f"{length!r}")


def read_start(values: Mapping[str, Any]):
    """The start curve of a run whose ``start`` is given
    (:func:`tightknot.knots.start_curve.read_start_curve`); ValueError naming the file."""
    from tightknot.knots.centerline_io import CenterlineError, parse_columns
    from tightknot.knots.start_curve import read_start_curve

    columns = values.get("columns")
    try:
        return read_start_curve(values["start"], values["knot"] == "closed",
                                values.get("units"),
                                None if columns is None else parse_columns(columns))
    except CenterlineError as err:
        # the parameter's name first, as every bad-input message has it
        raise CenterlineError(f"start: {err}") from None


def resolve_start(values: Mapping[str, Any]) -> dict[str, Any]:
    """The per-knot parameters of a run from a start curve (``values``: the checked
    parameters given, ``start`` among them): its knot type as detected (a ``knot_type``
    given must be among its candidates), and the rest length (``l0_over_d0`` or ``length``)
    when not given (:func:`tightknot.knots.start_curve.default_rest_length`). ValueError
    naming the file: unreadable, intersecting itself, another knot type."""
    from tightknot.knots import start_curve

    curve = read_start(values)
    d0 = values.get("diameter", Scene.diameter)
    start_curve.check_no_intersection(curve, d0)
    detected = start_curve.detect_knot_type(curve)
    if not start_curve.is_knot_name(detected):
        # "undefined ...": no generic projection, the curve nearly passes through itself.
        raise start_curve.StartCurveError(f"{curve.source}: its knot type cannot be "
                                          f"determined: {detected}")
    start_curve.check_knot_type(curve, detected, values.get("knot_type"))
    # The scene keeps the detected name: the topology checks compare it at every step.
    out: dict[str, Any] = {"knot_type": detected}
    key = "l0_over_d0" if curve.closed else "length"
    if values.get(key) is None:
        length = start_curve.default_rest_length(curve, detected, d0)
        out[key] = length / d0 if curve.closed else length
    return out


def build_scene(values: Mapping[str, Any], device: str = "cpu") -> KnotScene:
    """The :class:`~tightknot.knots.scenes.KnotScene` of resolved scene parameters
    ``values`` (every :class:`Scene` field of its knot given; other keys are ignored)."""
    from tightknot.contact.sectioned import SectionSettings
    from tightknot.knots import scenes
    from tightknot.rods.material import Material

    material = Material(values["youngs_modulus"], values["poisson"], values["density"])
    shift = bool(values.get("section_bend_shift", False))
    thinning = values.get("section_thinning", "edge")
    path = values.get("section_path", "auto")
    # The sectioned level's own options, each away from its default only with it.
    for key, value, default, why in (
            ("section_bend_shift", "on" if shift else "off", "off", ""),
            ("section_thinning", thinning, "edge", ""),
            ("section_path", path, "auto", " (the load path of its sections)")):
        if value != default and values["contact"] != "sectioned":
            raise ValueError(f"{key}: {value} needs contact sectioned{why}, got contact "
                             f"{values['contact']}")
    contact = (SectionSettings(max_mode=values["section_modes"], bend_shift=shift,
                               thinning=thinning)
               if values["contact"] == "sectioned" else values["contact"])
    if values.get("start") is not None:
        from tightknot.knots import start_curve

        curve = read_start(values)
        if curve.closed:
            return start_curve.closed_from_curve(
                curve, values["knot_type"], values["l0_over_d0"], values["diameter"],
                values["nodes"], material, twist=values["twist"], device=device,
                contact=contact)
        return start_curve.open_from_curve(
            curve, values["knot_type"], values["length"], values["diameter"], values["nodes"],
            material, twist=values["twist"], device=device, contact=contact,
            grip_length=values["grip_length"], grip_twist=values["grip_twist"])
    make = scenes.closed_knot if values["knot"] == "closed" else scenes.open_knot
    length = values["l0_over_d0"] if values["knot"] == "closed" else values["length"]
    grips = ({"grip_length": values["grip_length"], "grip_twist": values["grip_twist"]}
             if values["knot"] == "open" else {})
    shape = ({"start_shape": values.get("start_shape", StartFile.start_shape)}
             if values["knot"] == "closed" else {})
    return make(values["knot_type"], length, values["diameter"], values["nodes"], material,
                twist=values["twist"], contact=contact, device=device, **grips, **shape)
