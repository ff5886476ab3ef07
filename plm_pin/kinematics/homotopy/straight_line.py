r"""The square system as a straight-line program, traced once from the generic evaluation.

The generic evaluation (:func:`.evaluation.generic_system`) walks the form's joints and frames
at every call, multiplies complex :math:`4 \times 4` transforms, and computes the derivative of
every closure entry along every column. Most of those products are by constants: the zeros and
ones of a transform's last row and of a placement that only translates, the zeros of a
derivative matrix, the zero weights of a selection combination. This module runs that same
evaluation once, in Python, on symbols: each unknown, parameter and offset is a :class:`_Value`,
arithmetic on numbers stays numbers (so every product by a constant zero or one is folded), and
each arithmetic operation on a symbol becomes one instruction, recorded once however often it is
met (a shared subexpression is computed once). The result is a list of instructions
:math:`r_t = P_t\, r_a r_b + S_t\, r_c` over a register file holding the constants, the inputs
and the results, with :math:`P_t, S_t \in \{-1, 0, 1\}`: a product, a sum, a difference, or a
product added to or taken from a register (a product read once, by the sum after it, is fused
into that sum's instruction). Instructions whose result no output reads are dropped.

The program computes the same numbers as the generic evaluation, in the same order for each
sum, up to rounding (the compiled kernels contract products and sums into fused multiply-adds
where they choose). One compiled loop (:func:`system`) runs every form's program, so nothing
is compiled per mechanism. The test 3-RPR's program has 94 instructions, the general 6-6
platform's 409, the Delta's 488; an evaluation takes a fifth to a half of the generic one's
time (0.36 against 1.9 us on the 3-RPR, 1.3 against 2.7 us on the 6-6 platform).

Register file: ``[constants | x (n) | p (n_params) | cos p | sin p | b (n) | results]``; the
revolute parameters' cosines and sines (the program's ``angles``) are computed once per call,
before the instructions.
"""

from __future__ import annotations

import types
from typing import Any

import numpy as np
from numba import njit
from numba.core.registry import CPUDispatcher

from . import evaluation
from .form import PolynomialForm, Program

_ZERO, _ONE = 0, 1  # the registers of the constants 0 and 1, always first
_PRODUCT, _SUM = 0, 1  # instruction kinds while tracing: a * b, and a + s * b


class TracedBranch(TypeError):
    """The generic evaluation compared a traced value: it is not straight-line code."""


class _Tape:
    """The values met while tracing: constants, inputs, and instructions, each recorded once."""

    def __init__(self, n: int, n_params: int) -> None:
        # per value: ("const", c), ("input", slot), or (kind, a, b, sign) for an instruction on values a, b
        self.values: list[tuple] = []
        self.ids: dict[tuple, int] = {}
        self.constants: list[complex] = []
        self.n, self.n_params = n, n_params
        self.angles: set[int] = set()  # the parameters whose cosine and sine are read
        self.constant(0j)  # register _ZERO
        self.constant(1 + 0j)  # register _ONE

    def _id(self, key: tuple) -> int:
        hit = self.ids.get(key)
        if hit is None:
            self.values.append(key)
            hit = self.ids[key] = len(self.values) - 1
        return hit

    def constant(self, v: complex) -> int:
        key = ("const", complex(v))
        if key not in self.ids:
            self.constants.append(complex(v))
        return self._id(key)

    def input(self, slot: int) -> _Value:
        return _Value(self, self._id(("input", slot)))

    def operand(self, v: Any) -> int:
        return v.id if isinstance(v, _Value) else self.constant(v)

    def record(self, kind: int, a: Any, b: Any, sign: float) -> _Value:
        ia, ib = self.operand(a), self.operand(b)
        if (kind == _PRODUCT or sign > 0) and ib < ia:  # commutative: one record per pair
            ia, ib = ib, ia
        return _Value(self, self._id((kind, ia, ib, sign)))


def _number(v: Any) -> bool:
    return not isinstance(v, _Value)


def _add(a: Any, b: Any, sign: float) -> Any:
    """``a + sign * b``, folded when either side is a number zero."""
    if _number(a) and _number(b):
        return a + sign * b
    if _number(b) and b == 0:
        return a
    if _number(a) and a == 0:
        return b if sign > 0 else _mul(-1.0, b)
    tape = a.tape if isinstance(a, _Value) else b.tape
    return tape.record(_SUM, a, b, sign)


def _mul(a: Any, b: Any) -> Any:
    """``a * b``, folded when either side is a number zero or one."""
    if _number(a) and _number(b):
        return a * b
    if _number(a):
        a, b = b, a
    if _number(b):
        if b == 0:
            return 0j
        if b == 1:
            return a
    return a.tape.record(_PRODUCT, a, b, 1.0)


class _Value:
    """A traced value: an input, a constant met with one, or the result of a recorded instruction."""

    __slots__ = ("id", "tape")

    def __init__(self, tape: _Tape, id: int) -> None:
        self.tape, self.id = tape, id

    def __add__(self, o: Any) -> Any:
        return _add(self, o, 1.0)

    def __radd__(self, o: Any) -> Any:
        return _add(o, self, 1.0)

    def __sub__(self, o: Any) -> Any:
        return _add(self, o, -1.0)

    def __rsub__(self, o: Any) -> Any:
        return _add(o, self, -1.0)

    def __mul__(self, o: Any) -> Any:
        return _mul(self, o)

    def __rmul__(self, o: Any) -> Any:
        return _mul(o, self)

    def __neg__(self) -> Any:
        return _mul(-1.0, self)

    def _trig(self, which: int) -> _Value:
        key = self.tape.values[self.id]
        n, m = self.tape.n, self.tape.n_params
        if key[0] != "input" or not n <= key[1] < n + m:
            raise TracedBranch("cos and sin are taken of parameters only")
        self.tape.angles.add(key[1] - n)
        return self.tape.input(key[1] + which * m)

    def cos(self) -> _Value:  # np.cos on an object array element
        return self._trig(1)

    def sin(self) -> _Value:
        return self._trig(2)

    def __bool__(self) -> bool:
        raise TracedBranch("the evaluation branches on a traced value")

    def _compare(self, other: object) -> bool:
        return self.__bool__()

    __eq__ = __ne__ = __lt__ = __le__ = __gt__ = __ge__ = _compare
    __hash__ = object.__hash__


def _plain(module: types.ModuleType) -> dict[str, Any]:
    """The namespace of ``module`` with each compiled function replaced by its Python, calling each other."""
    namespace = dict(vars(module))
    for name, value in vars(module).items():
        if isinstance(value, CPUDispatcher):
            f = value.py_func
            namespace[name] = types.FunctionType(
                f.__code__, namespace, f.__name__, f.__defaults__, f.__closure__
            )
    return namespace


def straight_line(form: PolynomialForm) -> Program:
    """The straight-line program of ``form``'s square system and its Jacobian (see the module docstring).

    Raises:
        TracedBranch: the generic evaluation branched on a traced value (a change to it that this
            tracing does not support).
    """
    n, m = form.n, form.n_params
    tape = _Tape(n, m)
    plain = _plain(evaluation)
    ws = tuple(  # the generic evaluation's buffers, its complex ones holding Python numbers and values
        a.astype(object) if isinstance(a, np.ndarray) and a.dtype == np.complex128 else a
        for a in evaluation._new_workspace(form)
    )

    def inputs(first: int, count: int) -> np.ndarray:
        out = np.empty(count, dtype=object)
        for i in range(count):
            out[i] = tape.input(first + i)
        return out

    x, p, b = inputs(0, n), inputs(n, m), inputs(n + 3 * m, n)
    F, J = plain["generic_system"](x, p, b, ws, *form.kernel_args())
    outputs = np.concatenate([F[:, None], J], axis=1)
    program = _assemble(tape, [[tape.operand(v) for v in row] for row in outputs], n + 3 * m + n)
    return (*program, np.array(sorted(tape.angles), dtype=np.int32))


def _assemble(
    tape: _Tape, outputs: list[list[int]], n_inputs: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Registers for the values the outputs read, each product read once fused into the sum reading it."""
    values = tape.values
    is_instruction = [isinstance(key[0], int) for key in values]
    reads = np.zeros(len(values), dtype=np.int64)
    live = np.zeros(len(values), dtype=bool)
    for row in outputs:
        live[row] = True
        reads[row] += 2  # an output is never fused away
    for v in range(len(values) - 1, -1, -1):  # operands come before their instruction
        if live[v] and is_instruction[v]:
            for operand in values[v][1:3]:
                live[operand] = True
                reads[operand] += 1
    fused = np.zeros(len(values), dtype=bool)
    fuses = np.full(len(values), -1)  # per sum, the product it takes in
    for v, key in enumerate(values):
        if live[v] and is_instruction[v] and key[0] == _SUM:
            for side in (2, 1) if key[3] > 0 else (2,):  # a - b fuses b only
                w = key[side]
                if values[w][0] == _PRODUCT and reads[w] == 1 and not fused[w]:
                    fused[w], fuses[v] = True, side
                    break
    register = np.full(len(values), -1)
    n_constants = len(tape.constants)
    constant_register = {c: i for i, c in enumerate(tape.constants)}
    rows: list[tuple[int, int, int, float, float]] = []  # registers a, b, c; P, S
    for v, key in enumerate(values):
        if key[0] == "const":
            register[v] = constant_register[key[1]]
            continue
        if key[0] == "input":
            register[v] = n_constants + key[1]
            continue
        if not live[v] or fused[v]:
            continue
        kind, a, b, sign = key
        if kind == _PRODUCT:
            rows.append((register[a], register[b], _ZERO, 1.0, 0.0))
        elif fuses[v] > 0:
            product, other = (b, a) if fuses[v] == 2 else (a, b)
            pa, pb = values[product][1:3]
            rows.append((register[pa], register[pb], register[other], sign if fuses[v] == 2 else 1.0, 1.0))
        else:
            rows.append((register[a], _ONE, register[b], 1.0, sign))
        register[v] = n_constants + n_inputs + len(rows) - 1
    instructions = np.array([r[:3] for r in rows], dtype=np.int32).reshape(-1, 3)
    coefficients = np.array([r[3:] for r in rows], dtype=float).reshape(-1, 2)
    return (
        np.array(tape.constants, dtype=np.complex128),
        instructions,
        coefficients,
        register[np.array(outputs)].astype(np.int32),
    )


@njit(cache=True)
def workspace(n: int, n_params: int, program: Program) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The buffers :func:`system` writes into: the register file (constants written in), F and J."""
    constants, instructions = program[0], program[1]
    c = constants.shape[0]
    registers = np.zeros(c + 2 * n + 3 * n_params + instructions.shape[0], dtype=np.complex128)
    registers[:c] = constants
    return registers, np.zeros(n, dtype=np.complex128), np.zeros((n, n + n_params), dtype=np.complex128)


@njit(cache=True, fastmath=evaluation.FAST)
def system(
    x: np.ndarray, p: np.ndarray, b: np.ndarray, ws: tuple, program: Program
) -> tuple[np.ndarray, np.ndarray]:
    r"""Square system :math:`F(x; p) + b` (n,) and its Jacobian :math:`[F_x\ F_p]` (n, n + n_params).

    By ``program``. Both are buffers of ``ws`` (:func:`workspace`), overwritten by the next call
    (and ``J`` may be factored in place by the caller).
    """
    constants, instructions, coefficients, outputs, angles = program
    registers, F, J = ws
    c, n, m = constants.shape[0], x.shape[0], p.shape[0]
    for i in range(n):
        registers[c + i] = x[i]
        registers[c + n + 3 * m + i] = b[i]
    for i in range(m):
        registers[c + n + i] = p[i]
    for i in angles:
        registers[c + n + m + i] = np.cos(p[i])
        registers[c + n + 2 * m + i] = np.sin(p[i])
    first = c + 2 * n + 3 * m
    for k in range(instructions.shape[0]):
        product = registers[instructions[k, 0]] * registers[instructions[k, 1]]
        added = registers[instructions[k, 2]]
        registers[first + k] = coefficients[k, 0] * product + coefficients[k, 1] * added
    for i in range(n):
        F[i] = registers[outputs[i, 0]]
        for j in range(J.shape[1]):
            J[i, j] = registers[outputs[i, 1 + j]]
    return F, J
