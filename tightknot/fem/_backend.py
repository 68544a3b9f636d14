"""Lazy access to FElupe, the optional GPL-3.0 FEM backend.

FElupe is imported only here and only when a FEM function runs, so that ``import
tightknot`` (and ``import tightknot.fem``) never needs it. A missing FElupe raises
:class:`FelupeMissingError` (an ``ImportError``) with the install hint.
"""

from __future__ import annotations

from types import ModuleType

INSTALL_HINT = 'tightknot.fem needs FElupe (GPL-3.0, optional): pip install "tightknot[fem]"'


class FelupeMissingError(ImportError):
    """FElupe is not installed; the message says how to install it."""


def require_felupe() -> ModuleType:
    """Return the ``felupe`` module, or raise :class:`FelupeMissingError` with the hint."""
    try:
        import felupe
    except ImportError as err:  # the optional extra is not installed
        raise FelupeMissingError(INSTALL_HINT) from err
    return felupe


def felupe_version() -> str:
    """Version string of the installed FElupe (raises if it is missing)."""
    return str(require_felupe().__version__)


IPCTK_HINT = ('the two-deformable-body FEM scenes need ipctk (IPC Toolkit, MIT, optional): '
              'pip install "tightknot[fem]"')


def require_ipctk() -> ModuleType:
    """Return the ``ipctk`` module, or raise :class:`FelupeMissingError` with the hint.

    ipctk belongs to the same optional ``fem`` extra as FElupe, so a missing ipctk is the
    same kind of error (an ``ImportError`` naming the extra).
    """
    try:
        import ipctk
    except ImportError as err:  # the optional extra is not installed
        raise FelupeMissingError(IPCTK_HINT) from err
    return ipctk
