"""The FEM's and the rod model's profiles along the contact, side by side (issue 18): for
each scene of a cross-check report that reports profiles (the rigid indent's and wrap's rod
at the sectioned level; the soft wrap's rod A, the clasp's U, the soft crossing's rod A at
every level), the contact width fraction L_c, A/A0 and p_max/E against the rest arc length
s from the middle or apex, at each compared load level; the FEM's node layers solid with
markers, the rod model dashed (per vertex, or at the sectioned level per Gauss circle:
:func:`tightknot.fem.profile_compare.circle_profile`), one colour per level. The numbers
behind it are the report's ``profile_a`` comparisons
(:func:`tightknot.fem.profile_compare.along_contact`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from .figures import save_png_atomic

#: The plotted quantities: profile key, axis label.
QUANTITIES = (("contact_fraction", "L_c"), ("area_ratio", "A/A0"),
              ("peak_pressure_over_e", "p_max / E"))
#: The rigid scenes' titles, their load's label in the legend and the FEM step's key of it.
RIGID = {"indent": ("indent, rod from the crossing", "approach/D0", "approach_over_d0"),
         "wrap": ("wrap, rod from the middle", "T/(E D0^2)", "tension_over_e_d0sq")}
#: The soft scenes' titles and their load's label in the legend.
SCENES = {"soft_wrap": ("soft wrap, rod A", "T/(E D0^2)"),
          "clasp": ("clasp, U from its apex", "clamp travel/D0"),
          "soft_crossing": ("soft crossing, rod A", "w/D0")}


def _s(row: Mapping[str, float]) -> float:
    """A profile row's rest arc length [D0] (``z_over_d0`` along a straight rod)."""
    return row["s_over_d0"] if "s_over_d0" in row else row["z_over_d0"]


def _compared(soft: Mapping[str, Any], level: str, scene: str) -> list[tuple[Any, dict, dict]]:
    """(load, FEM step, rod step) of each level the comparison judged: the FEM's steps
    whose approach a compared row holds (the rod model ran at the FEM's levels, in
    order)."""
    entry = soft["levels"][level]["scenes"].get(scene)
    fem = soft["fem"].get(scene)
    if entry is None or fem is None:
        return []
    judged = {row["approach_over_d0"]: row["load"] for row in entry["comparison"]["levels"]}
    out = []
    for f, r in zip(fem["steps"], entry["rod_steps"], strict=True):
        if f["approach_over_d0"] in judged and "profile_a" in f and "profile_a" in r:
            out.append((judged[f["approach_over_d0"]], f, r))
    return out


def _rigid_compared(scenes: Mapping[str, Any], scene: str) -> list[tuple[Any, dict, dict]]:
    """(load, FEM step, rod step) of each level a rigid scene's comparison judged along
    the contact (the report's ``scenes`` entry; the rod's profile: the sectioned level)."""
    entry = scenes.get(scene)
    if entry is None or "fem_steps" not in entry:
        return []
    judged = {row["approach_over_d0"] for row in entry["comparison"]["levels"]
              if "profile_a" in row}
    key = RIGID[scene][2]
    return [(f[key], f, r) for f, r in zip(entry["fem_steps"], entry["rod_steps"], strict=True)
            if f["approach_over_d0"] in judged and "profile_a" in f and "profile_a" in r]


def plot_soft_profiles(soft: Mapping[str, Any], level: str,
                       path: str | os.PathLike[str]) -> list[str]:
    """Write the side-by-side profiles of a report's ``soft_scenes`` entry at contact
    level ``level`` (a key of its ``levels``) to the PNG ``path``; returns the scenes
    drawn (:func:`plot_profiles` without the rigid scenes)."""
    return plot_profiles(path, level, soft=soft)


def plot_profiles(path: str | os.PathLike[str], level: str,
                  soft: Mapping[str, Any] | None = None,
                  rigid: Mapping[str, Any] | None = None) -> list[str]:
    """Write the side-by-side profiles of a cross-check report to the PNG ``path``: its
    rigid ``scenes`` entry (``rigid``: indent and wrap, where they report profiles) and
    its ``soft_scenes`` entry (``soft``) at contact level ``level`` (a key of its
    ``levels``); returns the scenes drawn. ValueError where ``soft`` holds no such level
    or nothing holds a profile to draw."""
    import matplotlib.pyplot as plt
    import numpy as np

    compared: dict[str, list] = {}
    for scene in RIGID:
        compared[scene] = _rigid_compared(rigid, scene) if rigid is not None else []
    if soft is not None:
        if level not in soft.get("levels", {}):
            raise ValueError(f"the report's soft scenes hold no contact level {level!r} "
                             f"(it has {sorted(soft.get('levels', {}))})")
        for scene in SCENES:
            compared[scene] = _compared(soft, level, scene)
    titles = {**{k: v[:2] for k, v in RIGID.items()}, **SCENES}
    scenes = [s for s in titles if compared.get(s)]
    if not scenes:
        raise ValueError("the report holds no compared level with profiles")
    fig, axes = plt.subplots(len(scenes), len(QUANTITIES), squeeze=False,
                             figsize=(4.2 * len(QUANTITIES), 3.0 * len(scenes)))
    cmap = plt.get_cmap("viridis")
    for i, scene in enumerate(scenes):
        title, load_label = titles[scene]
        steps = compared[scene]
        ends = [max((_s(row) for row in prof if row["contact_fraction"] > 0.0),
                    default=0.0) for _, f, r in steps for prof in (f["profile_a"],
                                                                   r["profile_a"])]
        s_max = 1.3 * max(ends) if max(ends) > 0.0 else 1.0
        for k, (load, f, r) in enumerate(steps):
            color = cmap(0.85 * k / max(len(steps) - 1, 1))  # viridis's last yellow is faint
            for j, (key, label) in enumerate(QUANTITIES):
                ax = axes[i, j]
                for prof, style, who in ((f["profile_a"], {"marker": "o", "ms": 3,
                                                           "linestyle": "-"}, "FEM"),
                                         (r["profile_a"], {"linestyle": "--"}, "rod")):
                    s = np.array([_s(row) for row in prof])
                    v = np.array([row[key] for row in prof])
                    keep = s <= s_max
                    ax.plot(s[keep], v[keep], color=color, linewidth=1.2,
                            label=f"{who}, {load_label} {load:.3g}" if j == 0 else None,
                            **style)
                ax.set_xlabel("s / D0 (rest, from the middle or apex)")
                ax.set_ylabel(label)
                ax.set_title(f"{title}: {label}", fontsize=9)
                ax.grid(True, alpha=0.3)
        axes[i, 0].legend(fontsize=6, ncol=2)
    fig.suptitle(f"FEM (solid, node layers) against the rod model ({level} level, dashed)",
                 fontsize=10)
    fig.tight_layout()
    save_png_atomic(fig, path)
    return scenes
