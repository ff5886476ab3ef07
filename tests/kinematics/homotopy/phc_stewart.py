"""PHCpack oracle for a 6-6 platform: every real pose from the six leg lengths (run with the system python).

Reads JSON ``{"A": 6x3 base points [m], "B": 6x3 platform points in the platform frame [m],
"L": a list of leg-length sets, 6 lengths [m] each}`` on stdin. Solves
|p + R(q) B_i - A_i|^2 = L_i^2 with the rotation of a unit quaternion q = (w, x, y, z): the
first set by PHCpack's black-box solver, each further set by PHCpack's own tracker from the
first set's solutions (a parameter homotopy with PHCpack's random gamma: only the constant terms
change, so when the first set has the generic 80 regular solutions, their paths reach every
isolated solution of the next). Prints, for each set, its real solutions
(x, y, z, w, qx, qy, qz) and its solution count as one JSON list on the last line of stdout.
"""

import json
import sys

from phcpy.solutions import strsol2dict
from phcpy.solver import solve
from phcpy.trackers import track


def rotation(w, x, y, z):
    return [
        [f"({w}^2+{x}^2-{y}^2-{z}^2)", f"2*({x}*{y}-{w}*{z})", f"2*({x}*{z}+{w}*{y})"],
        [f"2*({x}*{y}+{w}*{z})", f"({w}^2-{x}^2+{y}^2-{z}^2)", f"2*({y}*{z}-{w}*{x})"],
        [f"2*({x}*{z}-{w}*{y})", f"2*({y}*{z}+{w}*{x})", f"({w}^2-{x}^2-{y}^2+{z}^2)"],
    ]


def equations(base, platform, lengths):
    """The leg equations at ``lengths`` and the unit quaternion's, as PHCpack strings."""
    R = rotation("qw", "qx", "qy", "qz")
    p = ["px", "py", "pz"]
    pols = []
    for A, B, L in zip(base, platform, lengths, strict=True):
        # |p|^2 + |B|^2 + |A|^2 + 2 p.(R B) - 2 A.p - 2 A.(R B) - L^2, with |R B| = |B| on unit q
        const = sum(b * b for b in B) + sum(a * a for a in A) - L * L
        terms = [f"px^2+py^2+pz^2+({const!r})"]
        for r in range(3):
            RB = "+".join(f"({B[c]!r})*{R[r][c]}" for c in range(3))
            terms.append(f"2*{p[r]}*({RB})")
            terms.append(f"-2*({A[r]!r})*{p[r]}")
            terms.append(f"-2*({A[r]!r})*({RB})")
        pols.append("+".join(terms).replace("+-", "-") + ";")
    pols.append("qw^2+qx^2+qy^2+qz^2-1;")
    return pols


def real_solutions(sols):
    out = []
    for s in sols:
        d = strsol2dict(s)
        v = [d[k] for k in ("px", "py", "pz", "qw", "qx", "qy", "qz")]
        if max(abs(c.imag) for c in v) < 1e-8:
            out.append([c.real for c in v])
    return {"real": out, "total": len(sols)}


def main():
    data = json.load(sys.stdin)
    start = equations(data["A"], data["B"], data["L"][0])
    start_sols = solve(start, verbose=True)  # PHCv2.4.86: verbose=False returns no solution
    results = [real_solutions(start_sols)]
    for lengths in data["L"][1:]:
        results.append(real_solutions(track(equations(data["A"], data["B"], lengths), start, start_sols)))
    sys.stdout.write("\n" + json.dumps(results) + "\n")


if __name__ == "__main__":
    main()
