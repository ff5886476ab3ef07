"""CAD-like copies of exact descriptions: link frames turned at random, coordinates rounded.

A CAD export writes every joint at its assembled pose, in link frames that are not aligned
with the mechanism's axes, to a few significant digits. The same is done here to an exact
URDF: each link's frame is turned by a random rotation :math:`Q_L` (the world link excepted),
which changes every number of the file but not the model (a joint origin :math:`T` becomes
:math:`Q_p^{-1} T Q_c`, its axis :math:`Q_c^T a`, an inertial, visual or collision origin
:math:`Q_L^{-1} T`), then every ``xyz`` and ``rpy`` is rounded to ``digits`` significant
digits. The rounded axes are then no longer exactly parallel, so a planar loop modelled in
3D closes only to the rounding (about 1e-7...1e-5 m at 6 digits).
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
from lxml import etree


def _origin(el: etree._Element | None) -> pin.SE3:
    if el is None:
        return pin.SE3.Identity()
    xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in el.get("rpy", "0 0 0").split()]
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))


def _write(parent: etree._Element, M: pin.SE3) -> None:
    el = parent.find("origin")
    if el is None:
        el = etree.SubElement(parent, "origin")
    el.set("xyz", " ".join(repr(float(v)) for v in M.translation))
    el.set("rpy", " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(M.rotation)))


def reframed(urdf: str, seed: int) -> str:
    """``urdf`` with every link frame but the root's turned by a random rotation (the same model)."""
    root = etree.fromstring(urdf.encode())
    children = {j.find("child").get("link") for j in root.iter("joint")}
    rng = np.random.default_rng(seed)
    Q = {}
    for link in root.iter("link"):
        name = link.get("name")
        Q[name] = (
            pin.SE3.Identity() if name not in children else pin.SE3(pin.exp3(rng.normal(size=3)), np.zeros(3))
        )
        for tag in ("inertial", "visual", "collision"):
            for el in link.findall(tag):
                _write(el, Q[name].inverse() * _origin(el.find("origin")))
    for joint in root.iter("joint"):
        p, c = joint.find("parent").get("link"), joint.find("child").get("link")
        _write(joint, Q[p].inverse() * _origin(joint.find("origin")) * Q[c])
        axis = joint.find("axis")
        if axis is not None:
            a = Q[c].rotation.T @ np.array([float(v) for v in axis.get("xyz").split()])
            axis.set("xyz", " ".join(repr(float(v)) for v in a))
    return etree.tostring(root, encoding="unicode")


def rounded(urdf: str, digits: int = 6) -> str:
    """``urdf`` with the ``xyz`` and ``rpy`` numbers rounded to ``digits`` significant digits."""

    def one(match: re.Match[str]) -> str:
        values = " ".join(f"{float(v):.{digits}g}" for v in match.group(2).split())
        return f'{match.group(1)}="{values}"'

    return re.sub(r'\b(xyz|rpy)="([^"]*)"', one, urdf)
