r"""Loop closures written as onshape-to-robot writes them: ``closing_<name>_1`` / ``closing_<name>_2`` frames.

onshape-to-robot (Rhoban) turns an Onshape mate named ``closing_<name>`` into two frames,
``closing_<name>_1`` and ``closing_<name>_2``, one on each mated part, at the mate connector
(its z axis the mate's axis). In a URDF a frame is a massless *dummy link* hung on its part
by a ``fixed`` joint named ``<frame>_frame``; in an MJCF it is a ``site``, and the closure is
an equality between the two sites (``connect``, or ``weld`` for a fastened mate). A revolute
mate also gets ``closing_<name>_1_z`` / ``closing_<name>_2_z``, 0.1 m along the mate's z axis,
closed by a second ``connect``: two point closures fix the axis as a hinge does (6 rows of
rank 5).

A URDF does not say which kind of mate a pair closes, so each pair is read as a ``point``
closure (a ball or, with its ``_z`` pair, a hinge), named ``closing_<name>`` (and
``closing_<name>_z``); a fastened mate needs a sidecar saying ``type: weld``. The MJCF
export says it (``weld``), and :mod:`plm_pin.description.mjcf` reads it from there, naming
the unnamed equalities after their frames in the same way.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from ..exceptions import DescriptionError
from .sidecar import ClosureSpec

CLOSING = re.compile(r"^(?P<base>closing_.+)_(?P<side>[12])(?P<z>_z)?$")
"""Name of an onshape-to-robot closing frame: ``closing_<name>_<1|2>``, with ``_z`` for the axis pair."""


def closing_name(frame1: str, frame2: str) -> str | None:
    """The closure name of two closing frames of one pair (``closing_<name>``, ``..._z``), else None."""
    a, b = CLOSING.match(frame1), CLOSING.match(frame2)
    if a is None or b is None or (a["base"], a["z"]) != (b["base"], b["z"]) or a["side"] == b["side"]:
        return None
    return a["base"] + (a["z"] or "")


def closing_closures(frames: Iterable[str], label: str | None = None) -> tuple[ClosureSpec, ...]:
    """The point closures of the closing frames among ``frames``, in the order of their first frame.

    Args:
        frames: frame (URDF link) names.
        label: the file, for messages.

    Raises:
        DescriptionError: when a closing frame has no partner (``closing_a_1`` without
            ``closing_a_2``).
    """
    pairs: dict[tuple[str, str], dict[str, str]] = {}
    for frame in frames:
        match = CLOSING.match(frame)
        if match is not None:
            pairs.setdefault((match["base"], match["z"] or ""), {})[match["side"]] = frame
    out = []
    for (base, z), sides in pairs.items():
        if len(sides) != 2:
            ((side, frame),) = sides.items()
            partner = f"{base}_{'2' if side == '1' else '1'}{z}"
            raise DescriptionError(
                f"closing frame {frame!r} has no partner {partner!r}: onshape-to-robot closes a loop "
                "between the two frames of a closing_<name> mate",
                label,
            )
        out.append(ClosureSpec(name=base + z, frames=(sides["1"], sides["2"]), type="point"))
    return tuple(out)
