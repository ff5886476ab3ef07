"""Mechanism families: one package per family, with its parametric builder and its own analyses.

- :mod:`plm_pin.families.prrrp`: 2-PRRRP planar tables on one stator (Harada 2011, 2015):
  builder, layout, assembly and working modes, mode-change planners, complex singularity.
- :mod:`plm_pin.families.pss`: n-PSS spatial platforms (Zhao 2011).
- :mod:`plm_pin.families.star_triangle`: 3-PRP star-triangle (Enferadi 2017).
- :mod:`plm_pin.families.classic`: four-bar and five-bar test mechanisms.

The named presets built from them are in :mod:`plm_pin.models`; the generic closed-chain
machinery they use is in :mod:`plm_pin.kinematics`. Each family's names are public in its own
package only: ``from plm_pin.families.prrrp import build_2prrrp``. This package imports none
of them: a family is loaded when it is used (building a preset, planning a mode change), never
by ``import plm_pin`` nor by loading a shipped description.
"""

__all__: list[str] = []
