"""The friction branches, one update per branch (cost O(n) per call).

Branch i has stiffness k[i] (N/m), elastic range eta[i] (m) and elongation
u[i] (m), |u[i]| <= eta[i]. Moving the point by a monotone increment dx moves
every elongation by the *play* (stop) operator, the exact solution of
u' + d psi_[-eta, eta](u) ∋ x' over that increment:

    u[i] <- clip(u[i] + dx, -eta[i], eta[i])

The loops are branch-free (min/max) over contiguous arrays. ``k``, ``eta``
and ``u`` are all ``None`` when the scene has no branches.

The entry points :func:`branch_force`, :func:`move`, :func:`piece`,
:func:`stored_energy` and :func:`write_elongations` also take the memory
stack (``kernels/stack.py``) in place of the arrays: its parameters as ``k``
(a 2-D array for n branches, a tuple for the continuum), ``eta`` None and
its state as ``u``. numba picks the implementation from the types when it
compiles a stepper, so a step costs the same as if written for one kernel.
"""
import numpy as np
from numba.core import types
from numba.core.errors import TypingError
from numba.extending import overload

from .._jit import kernel
from . import stack


@kernel
def branch_force(k, u):
    """sum_i k_i u_i (N); ``k`` may also be memory-stack parameters (``u`` its state)."""
    return _branch_force(k, u)


def _branch_force(k, u):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_branch_force)
def _branch_force_overload(k, u):
    if isinstance(k, types.NoneType):
        return lambda k, u: 0.0
    if _is_stack(k):  # the memory stack's parameters (kernels/stack.py)
        return lambda k, u: stack.force(k, u)

    def impl(k, u):
        force = 0.0
        for i in range(k.shape[0]):
            force += k[i] * u[i]
        return force

    return impl


@kernel
def branch_bounds(k, eta):
    """(sum |k_i|, max eta_i) over every branch, whatever the kernel (``kernels/showable.py``)."""
    return _branch_bounds(k, eta)


def _branch_bounds(k, eta):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_branch_bounds)
def _branch_bounds_overload(k, eta):
    if isinstance(k, types.NoneType):
        return lambda k, eta: (0.0, 0.0)
    if _is_stack(k):
        return lambda k, eta: stack.bounds(k)

    def impl(k, eta):
        total = 0.0
        largest = 0.0
        for i in range(k.shape[0]):
            total += abs(k[i])
            largest = max(largest, abs(eta[i]))
        return total, largest

    return impl


@kernel
def write_elongations(k, u, out):
    """Write the elongations u_i (m) into ``out`` (length n, the scene's order)."""
    _write_elongations(k, u, out)


def _write_elongations(k, u, out):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_write_elongations)
def _write_elongations_overload(k, u, out):
    if isinstance(k, types.BaseTuple):
        raise TypingError("the continuum has no list of elongations")
    if _is_stack(k):
        return lambda k, u, out: stack.elongations(k, u, out)

    def impl(k, u, out):
        for i in range(u.shape[0]):  # not out[:] = u, whose shape check formats its message with libm's log10
            out[i] = u[i]

    return impl


@kernel
def record_elongations(k, u, out):
    """:func:`write_elongations` where ``out`` has room for them; nothing where it has none (they were not asked
    for), nor for a scene without branches or for the continuum, which have no list of elongations. The time loop
    calls it for every scene (``kernels/loop.py``)."""
    _record_elongations(k, u, out)


def _record_elongations(k, u, out):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_record_elongations)
def _record_elongations_overload(k, u, out):
    if k is None or isinstance(k, (types.NoneType, types.BaseTuple)):
        return lambda k, u, out: None

    def impl(k, u, out):
        if out.shape[0] > 0:
            _write_elongations(k, u, out)

    return impl


@kernel
def shift(k, eta, u, dx):
    """Apply the play operator for the increment ``dx`` in place; return the new sum k_i u_i."""
    if k is None:
        return 0.0
    force = 0.0
    for i in range(k.shape[0]):
        ui = min(max(u[i] + dx, -eta[i]), eta[i])
        u[i] = ui
        force += k[i] * ui
    return force


@kernel
def shift_slipping(k, eta, u, dx):
    """:func:`shift`, also returning the work dissipated by the sliders, sum_i alpha_i |slip_i| (J).

    slip_i = u_i + dx - clip(u_i + dx) is the slider's own displacement over
    the increment; alpha_i = k_i eta_i its threshold.
    """
    force = 0.0
    dissipated = 0.0
    for i in range(k.shape[0]):
        moved = u[i] + dx
        ui = min(max(moved, -eta[i]), eta[i])
        u[i] = ui
        force += k[i] * ui
        dissipated += k[i] * eta[i] * abs(moved - ui)
    return force, dissipated


@kernel
def move(k, eta, u, dx, energy):
    """:func:`shift`; with an ``energy`` account (not None), add the sliders' dissipation to energy[1].

    With memory-stack parameters as ``k`` (and ``eta`` None) the stack moves
    instead, with the same account.
    """
    return _move(k, eta, u, dx, energy)


def _move(k, eta, u, dx, energy):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_move)
def _move_overload(k, eta, u, dx, energy):
    if isinstance(k, types.NoneType):
        return lambda k, eta, u, dx, energy: 0.0
    if _is_stack(k):
        return lambda k, eta, u, dx, energy: stack.move(k, u, dx, energy)

    def impl(k, eta, u, dx, energy):
        if energy is None:
            return shift(k, eta, u, dx)
        force, dissipated = shift_slipping(k, eta, u, dx)
        energy[1] += dissipated
        return force

    return impl


@kernel
def piece(k, eta, u, dx, direction):
    """The branch force as a function of the increment, around ``dx``, in ``direction`` (+1 or -1).

    Returns ``(force, stiffness, room)``: the force sum_i k_i clip(u_i + dx) at
    ``dx``; the stiffness sum of the branches still sticking just beyond ``dx``
    in ``direction`` (the one-sided slope); and ``room`` >= 0, how far the
    increment can go beyond ``dx`` before the next branch starts to slip
    (``inf`` when none is left). ``u`` is not modified. ``dx`` is 0 or of the
    sign of ``direction``.
    """
    return _piece(k, eta, u, dx, direction)


def _piece(k, eta, u, dx, direction):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_piece)
def _piece_overload(k, eta, u, dx, direction):
    if isinstance(k, types.NoneType):
        return lambda k, eta, u, dx, direction: (0.0, 0.0, np.inf)
    if _is_stack(k):
        return lambda k, eta, u, dx, direction: stack.peek(k, u, dx, direction)

    def impl(k, eta, u, dx, direction):
        force = 0.0
        stiffness = 0.0
        room = np.inf
        for i in range(k.shape[0]):
            moved = u[i] + dx
            force += k[i] * min(max(moved, -eta[i]), eta[i])
            gap = eta[i] - direction * moved  # > 0 while branch i sticks beyond dx
            sticking = gap > 0.0
            stiffness += k[i] * sticking
            room = min(room, gap if sticking else np.inf)
        return force, stiffness, room

    return impl


@kernel
def branch_count(k):
    """n, the number of branches (0 without; -1 for the continuum, which has infinitely many)."""
    return _branch_count(k)


def _branch_count(k):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_branch_count)
def _branch_count_overload(k):
    if isinstance(k, types.NoneType):
        return lambda k: 0
    if isinstance(k, types.BaseTuple):
        return lambda k: -1
    if k.ndim == 2:
        return lambda k: k.shape[1] - 1
    return lambda k: k.shape[0]


def _is_stack(k):
    """At typing time: whether ``k`` is memory-stack parameters (2-D array, or the continuum's tuple)."""
    return isinstance(k, types.BaseTuple) or (isinstance(k, types.Array) and k.ndim == 2)


@kernel
def stored_energy(k, u):
    """sum_i k_i u_i^2 / 2 (J)."""
    return _stored_energy(k, u)


def _stored_energy(k, u):
    raise NotImplementedError  # compiled only: see the overload below


@overload(_stored_energy)
def _stored_energy_overload(k, u):
    if isinstance(k, types.NoneType):
        return lambda k, u: 0.0
    if _is_stack(k):
        return lambda k, u: stack.stored_energy(k, u)

    def impl(k, u):
        energy = 0.0
        for i in range(k.shape[0]):
            energy += 0.5 * k[i] * u[i] * u[i]
        return energy

    return impl
