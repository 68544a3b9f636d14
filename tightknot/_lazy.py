"""Lazy public names of a package (PEP 562): ``from tightknot.rods import RodBuilder``
imports ``tightknot.rods.builder`` when the name is first asked for, so that importing a
package costs only what is used (the CLI starts without Warp)."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_exports(package: str, exports: dict[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]], list[str]]:
    """``(__getattr__, __dir__, __all__)`` for ``package`` whose public names live in the
    modules ``exports[name]`` (module paths relative to the package, e.g. ``".builder"``)."""

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        globals_of = importlib.import_module(package).__dict__
        globals_of[name] = value  # asked once
        return value

    def __dir__() -> list[str]:
        return sorted(set(importlib.import_module(package).__dict__) | set(exports))

    return __getattr__, __dir__, sorted(exports)
