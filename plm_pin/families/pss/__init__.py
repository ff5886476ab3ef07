"""n-PSS spatial parallel manipulators (Zhao 2011's 8-PSS and its 6-PSS counterpart)."""

from .builder import build_pss, pss_inverse_kinematics

__all__ = ["build_pss", "pss_inverse_kinematics"]
