"""Compile plm_pin's numba kernels into their on-disk cache before the test workers start.

``tests/conftest.py`` runs one process per part below when ``make test`` starts its two
pytest-xdist workers. On a cold cache each worker would otherwise compile the same kernels,
up to three minutes of CPU each; the parts run side by side (complete FK about 75 s, the
kinematics and dynamics kernels about 100 s), and the workers load what they wrote. Each part
makes calls the tests make anyway; a kernel signature missed here compiles in the worker that
needs it, as before. With a warm cache the parts take about 2 s.

Run ``python tests/compile_kernels.py kinematics dynamics`` to compile some parts by hand.
"""

from __future__ import annotations

import sys

import numpy as np

import plm_pin
from plm_pin import kinematics as kin


def kinematics() -> None:
    """Inverse and forward kinematics, Jacobians and a map with every metric, on the kernels."""
    from plm_pin.workspace.maps import workspace_map

    mech = plm_pin.load("harada2011_3d4m")
    sol = kin.inverse_kinematics(mech, kin.task_pose(mech, mech.q_ref) + 0.002)
    kin.forward_kinematics(mech, sol.actuators, sol.q, all_modes=False)
    kin.closed_chain_jacobians(mech, sol.q)
    x, y = kin.task_pose(mech, mech.q_ref)[:2]
    workspace_map(mech, ("x", "y"), (np.linspace(x - 0.01, x + 0.01, 4), np.linspace(y - 0.01, y + 0.01, 4)))


def dynamics() -> None:
    """A simulation whose samples take the compiled path."""
    from plm_pin.dynamics.simulation import simulate

    mech = plm_pin.load("fourbar")
    simulate(mech, mech.q_ref, duration=0.05, dt=1e-3)


def homotopy() -> None:
    """Complete forward kinematics: generic solve, tracking and interval certificates."""
    mech = plm_pin.load("fivebar")
    kin.forward_kinematics(mech, mech.actuator_positions(mech.q_ref))


PARTS = {"kinematics": kinematics, "dynamics": dynamics, "homotopy": homotopy}

if __name__ == "__main__":
    for name in sys.argv[1:]:
        PARTS[name]()
