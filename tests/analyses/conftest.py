"""Fixtures of the study tests: those of the report tests (a user's description on disk)."""

from tests.report.conftest import user_fivebar

__all__ = ["user_fivebar"]
