"""The stress suite's switch: ``--run-extremes`` runs every case (``make test-extremes``);
without it only the cases not marked ``extremes`` run (the fast subset of ``make test``)."""

from __future__ import annotations

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--run-extremes", action="store_true", default=False,
                     help="run the whole numerical-stability stress suite (tests/extremes)")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--run-extremes"):
        return
    skip = pytest.mark.skip(reason="stress case: run with --run-extremes (make test-extremes)")
    for item in items:
        if item.get_closest_marker("extremes") is not None:
            item.add_marker(skip)
