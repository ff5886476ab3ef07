"""Studies shipped inside the wheel: the generic ``overview``, copied from ``analyses/overview.py`` at build.

``plm-pin report`` uses the package ``analyses`` (the studies of a source checkout) when it is
importable, and this package otherwise, so an installed wheel can still write the overview of
any mechanism. The paper studies need the checkout (see :mod:`plm_pin.report.study`).
"""
