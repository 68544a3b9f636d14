"""Verification cases with closed-form or independent references (``tightknot verify``)."""

from tightknot.verification.cases import CASES, VerifyRow, run_all

__all__ = ["CASES", "VerifyRow", "run_all"]
