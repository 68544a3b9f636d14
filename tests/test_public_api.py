"""The public API: every exported name resolves (the README's tour itself runs in
tests/test_examples.py)."""

from __future__ import annotations

import importlib

import pytest

PACKAGES = ("tightknot", "tightknot.rods", "tightknot.contact", "tightknot.solvers",
            "tightknot.knots", "tightknot.loading", "tightknot.study", "tightknot.viz",
            "tightknot.sweep")


@pytest.mark.parametrize("package", PACKAGES)
def test_every_exported_name_resolves(package: str) -> None:
    mod = importlib.import_module(package)
    assert mod.__all__, f"{package} exports nothing"
    for name in mod.__all__:
        assert getattr(mod, name) is not None, f"{package}.{name}"
        assert name in dir(mod)
    with pytest.raises(AttributeError, match="no attribute"):
        mod.not_a_name  # noqa: B018


def test_the_readme_names_its_subpackages_rightly() -> None:
    # "from tightknot.rods import RodBuilder" (the README's list of the lower layers).
    from tightknot.contact import ContactLayer, contact_report  # noqa: F401
    from tightknot.rods import BoundaryConditions, Material, RodBuilder, State  # noqa: F401
    from tightknot.solvers import RodSystem, continuation, implicit_euler_step, newton  # noqa: F401
    from tightknot.viz import NullLogger, RerunLogger  # noqa: F401
