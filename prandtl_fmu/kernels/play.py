"""The friction branches, one update per branch (cost O(n) per call).

Branch i has stiffness k[i] (N/m), elastic range eta[i] (m) and elongation
u[i] (m), |u[i]| <= eta[i]. Moving the point by a monotone increment dx moves
every elongation by the *play* (stop) operator, the exact solution of
u' + d psi_[-eta, eta](u) ∋ x' over that increment:

    u[i] <- clip(u[i] + dx, -eta[i], eta[i])

The loops are branch-free (min/max) over contiguous arrays. ``k``, ``eta``
and ``u`` are all ``None`` when the scene has no branches.
"""
import numpy as np

from .._jit import kernel


@kernel
def branch_force(k, u):
    """sum_i k_i u_i (N)."""
    if k is None:
        return 0.0
    force = 0.0
    for i in range(k.shape[0]):
        force += k[i] * u[i]
    return force


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
    """:func:`shift`; with an ``energy`` account (not None), add the sliders' dissipation to energy[1]."""
    if k is None:
        return 0.0
    if energy is None:
        return shift(k, eta, u, dx)
    force, dissipated = shift_slipping(k, eta, u, dx)
    energy[1] += dissipated
    return force


@kernel
def piece(k, eta, u, dx, direction):
    """The branch force as a function of the increment, around ``dx``, in ``direction`` (+1 or -1).

    Returns ``(force, stiffness, room)``: the force sum_i k_i clip(u_i + dx) at
    ``dx``; the stiffness sum of the branches still sticking just beyond ``dx``
    in ``direction`` (the one-sided slope); and ``room`` >= 0, how far the
    increment can go beyond ``dx`` before the next branch starts to slip
    (``inf`` when none is left). ``u`` is not modified.
    """
    if k is None:
        return 0.0, 0.0, np.inf
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


@kernel
def stored_energy(k, u):
    """sum_i k_i u_i^2 / 2 (J)."""
    if k is None:
        return 0.0
    energy = 0.0
    for i in range(k.shape[0]):
        energy += 0.5 * k[i] * u[i] * u[i]
    return energy
