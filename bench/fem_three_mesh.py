"""The FEM's three-mesh table of a two-soft-rod scene at every load level, and the rod
model against each mesh (ground rule 4: the FEM's own spread beside a comparison).

    tightknot fem soft_wrap --mesh fine --no-compare --no-convergence --json F
    python bench/fem_three_mesh.py soft_wrap --json C M F --rod sectioned --out J

Each ``--json`` file is a scene result (``tightknot fem SCENE --json``) or a cross-check
report (``tightknot fem crosscheck --json``: its ``fem_results`` hold the scene on the
report's mesh and, as ``SCENE@coarse``, on the spread mesh); the first result found for a
mesh is used. The meshes must share the load levels (the scene's defaults). ``--rod`` runs
the rod model once at those levels and compares it with each mesh as the cross-check does
(:func:`tightknot.fem.crosscheck_soft.compare`), so that its error can be read beside the
FEM's own change with the mesh.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
from pathlib import Path
from typing import Any

from tightknot.fem.crosscheck_soft import LOAD_KEYS


def scene_results(paths: list[Path], scene: str) -> dict[str, dict[str, Any]]:
    """The scene's FEM results in ``paths``, by mesh level (the first one per mesh)."""
    found: dict[str, dict[str, Any]] = {}
    for path in paths:
        data = json.loads(path.read_text())
        candidates = ([data] if data.get("scene") == scene else
                      [v for k, v in (data.get("fem_results") or {}).items()
                       if k == scene or k.startswith(f"{scene}@")])
        for result in candidates:
            found.setdefault(result["mesh"]["level"], result)
    return found


def _headline(scene: str) -> tuple[str, ...]:
    """The keys the scene's own module compares across meshes."""
    return importlib.import_module(f"tightknot.fem.scenes.{scene}").HEADLINE_KEYS


def run(scene: str, paths: list[Path], rod: str | None) -> dict[str, Any]:
    """The table (and with ``rod`` the rod model's comparison with each mesh)."""
    from tightknot.fem.crosscheck_soft import compare, rod_runs
    from tightknot.fem.scenes._common import MESH_LEVELS, level_table

    results = scene_results(paths, scene)
    meshes = [m for m in MESH_LEVELS if m in results]
    out: dict[str, Any] = {
        "scene": scene,
        "meshes": {m: {**results[m]["mesh"], "wall_time_s": results[m]["wall_time_s"],
                       "newton_iterations_total": results[m].get("newton_iterations_total")}
                   for m in meshes},
        "levels": level_table(results, _headline(scene), LOAD_KEYS[scene]),
    }
    if rod is not None:
        start = time.perf_counter()
        runs = rod_runs({scene: results[meshes[-1]]}, rod, scenes=(scene,))
        out["rod"] = {"contact": rod, "wall_time_s": time.perf_counter() - start,
                      "against": {m: compare(scene, results[m]["steps"],
                                             runs[scene]["steps"], None)["levels"]
                                  for m in meshes}}
    return out


def _markdown(out: dict[str, Any]) -> str:
    meshes = list(out["meshes"])
    finest, others = meshes[-1], meshes[:-1][::-1]
    lines = [f"{out['scene']}: " + ", ".join(
        f"{m} {out['meshes'][m]['dofs']} dofs {out['meshes'][m]['wall_time_s']:.0f} s"
        for m in meshes), ""]
    keys = list(out["levels"][0]["values"])
    head = "| load | " + " | ".join(f"{k} ({finest}; {', '.join(others)})" for k in keys)
    lines += [head + " |", "|---" * (len(keys) + 1) + "|"]
    for row in out["levels"]:
        cells = []
        for k in keys:
            v = row["values"][k]
            rel = [row["relative"][m][k] for m in others]
            cells.append("" if v is None else f"{v:.4g}; " + ", ".join(
                "-" if r is None else f"{100 * r:+.1f} %" for r in rel))
        lines.append(f"| {row['load']:.4g} | " + " | ".join(cells) + " |")
    if "rod" in out:
        lines += ["", f"rod model ({out['rod']['contact']}, {out['rod']['wall_time_s']:.1f} s)"
                  " against each mesh: force, A/A0 [points]", "",
                  "| load | " + " | ".join(meshes) + " |", "|---" * (len(meshes) + 1) + "|"]
        by_mesh = out["rod"]["against"]
        for k, row in enumerate(by_mesh[finest]):
            lines.append(f"| {row['load']:.4g} | " + " | ".join(
                f"{100 * by_mesh[m][k]['force_rel']:+.1f} %, "
                f"{100 * by_mesh[m][k]['area_points']:+.1f}" for m in meshes) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", choices=sorted(LOAD_KEYS))
    ap.add_argument("--json", nargs="+", type=Path, required=True,
                    help="scene results or cross-check reports holding the meshes")
    ap.add_argument("--rod", choices=["compliant", "smoothed", "sectioned"],
                    help="also run the rod model at this contact level")
    ap.add_argument("--out", type=Path, help="write the table as JSON")
    args = ap.parse_args(argv)
    try:
        out = run(args.scene, args.json, args.rod)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(_markdown(out))
    if args.out:
        from tightknot.fem.scenes._common import finite

        tmp = args.out.with_suffix(args.out.suffix + ".tmp")
        tmp.write_text(json.dumps(finite(out), indent=1))
        tmp.replace(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
