"""Parametric mechanisms from their leg types: planar 3-RPR/PRR/RRR/PRP, hexapods, the 3-UPU, the Delta.

Each mechanism has a builder returning the URDF tree and the sidecar (``build_planar``, ...:
the form presets, sweeps and :func:`plm_pin.build_mechanism` take) and a function writing both
files into a folder and returning the URDF's path (``planar``, ...), for :func:`plm_pin.load`.
"""

from .delta import build_delta, delta
from .hexapod import HEXAPOD_LEGS, build_hexapod, hexapod
from .planar import PLANAR_LEGS, build_planar, planar
from .translational import TRANSLATIONAL_LEGS, build_translational, translational

__all__ = [
    "HEXAPOD_LEGS",
    "PLANAR_LEGS",
    "TRANSLATIONAL_LEGS",
    "build_delta",
    "build_hexapod",
    "build_planar",
    "build_translational",
    "delta",
    "hexapod",
    "planar",
    "translational",
]
