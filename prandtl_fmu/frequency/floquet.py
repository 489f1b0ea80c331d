"""Stability of a periodic state: Floquet multipliers from the monodromy of one period.

The choice: the monodromy matrix by finite differences, each column one period integrated with the project's
own ``implicit`` network stepper (``network/kernels.py``: an exact active-set method for the branches, backward
Euler in time) from the harmonic balance's state at t = 0 with x or v of one node with a mass perturbed, the
orbit's own period integrated beside it; Phi[:, k] = (state(T) perturbed - state(T)) / epsilon over the x and v
of the nodes with a mass (a massless node follows them; a branch's elongation u is carried from the orbit's,
u at t = 0 from the sampled cycle of ``aft.py``). Why not Hill's method: its eigenvalues come from the Jacobian
of the harmonic balance, whose truncation puts spurious eigenvalues beside the true ones, and with the kinks of
slipping branches the sorting of the physical ones is not reliable; the monodromy sees the slips and sticks as
they happen (the perturbed runs cross the same events a little earlier or later).

Under base excitation the runs are in absolute coordinates, the ground a massless node whose motion
y = Y0 cos(omega t) is imposed at each step (:func:`_based_period`), and the state in and out relative
(z = x - y): what the balance solves for. With one node with a mass this agrees with integrating the relative
coordinate under its force m omega^2 Y0 cos(omega t) (:func:`forced_scene`) to 2e-6 at 4096 steps on a mass
on a Jenkins element; the two discretize the base's motion differently and differ by up to 1 % at 256 steps.

Backward Euler damps: with M steps per period a multiplier is shrunk by about exp(-(2 pi)^2 / (2 M)
(omega_n / omega)^2) per period, omega_n the motion's frequency. The monodromy is taken at M and 2 M steps and
extrapolated (Richardson, first order: 2 Phi_2M - Phi_M), which leaves an error of order 1 / M^2.

A point is ``stable`` when every multiplier has |mu| <= 1 + MARGIN (MARGIN covers the finite differences and
the extrapolation; a fold, where one multiplier crosses 1, is stable to either side within it).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

STEPS = 256
MARGIN = 2e-3
PERTURBATION = 1e-6


def orbit_start(balance, q_free, omega) -> tuple:
    """(x, v, u) at t = 0 of the harmonic balance's orbit: per node, and per network element (u of branches)."""
    full = balance.full(q_free)
    coefficients = full.reshape(balance.system.n, balance.L)
    H = balance.H
    x = coefficients[:, 0] + coefficients[:, 1::2].sum(axis=1)
    v = omega * (coefficients[:, 2::2] * np.arange(1, H + 1)).sum(axis=1)
    balance.nonlinear(full, omega)  # the elongations of the branches at sample 0
    u = np.zeros(len(balance.system.network.elements))
    u[balance.system.branch_index] = balance.elongations
    for group, elongations in zip(balance.system.series, balance.series_u):
        u[group.index] = elongations
    return x, v, u


def multipliers(balance, q_free, omega, steps: int = STEPS) -> np.ndarray:
    """The Floquet multipliers (complex, (2 n_mass,)) of the orbit of ``balance`` at ``omega`` (rad/s)."""
    coarse = _monodromy(balance, q_free, omega, steps)
    fine = _monodromy(balance, q_free, omega, 2 * steps)
    return np.linalg.eigvals(2.0 * fine - coarse)


def is_stable(values: np.ndarray) -> bool:
    return bool(np.max(np.abs(values)) <= 1.0 + MARGIN)


def _monodromy(balance, q_free, omega, steps) -> np.ndarray:
    system = balance.system
    x, v, u = orbit_start(balance, q_free, omega)
    run_period = (_forced_period if balance.base_amplitude is None else _based_period)(balance, omega, steps, u)
    massive = system.massive
    size = max(float(np.max(np.abs(x))), float(np.max(np.abs(v))) / omega, 1e-300)
    epsilon = PERTURBATION * size
    base = run_period(x, v)
    count = len(massive)
    columns = []
    for k in range(2 * count):
        dx, dv = np.zeros(system.n), np.zeros(system.n)
        if k < count:
            dx[massive[k]] = epsilon
        else:
            dv[massive[k - count]] = epsilon * omega
        columns.append((run_period(x + dx, v + dv) - base) / epsilon)
    rows = np.concatenate((np.ones(count), np.full(count, omega)))
    return np.array(columns).T / rows[:, None]  # in the coordinates (x, v / omega): dimensionless


def _forced_period(balance, omega, steps, u):
    """One period of ``steps`` implicit steps under the force at the load's node, from (x, v) and the branches'
    ``u`` at t = 0: a function of (x, v) giving (x, v) of the nodes with a mass at t = T."""
    from ..network.driver import NetworkElement
    from ..scene_tables import Solver

    period = 2.0 * math.pi / omega
    h = period / steps
    element = NetworkElement(forced_scene(balance, omega, Solver("implicit", h, period, h)), "implicit", h)
    massive = balance.system.massive

    def run(x, v):
        element.reset()
        element.x[:] = x
        element.v[:] = v
        element.u[:] = u
        element.piece[:] = 0
        element.time = 0.0
        element.advance(period, 0.0, scene_load=True)
        return np.concatenate((element.x[massive], element.v[massive]))

    return run


def _based_period(balance, omega, steps, u):
    """:func:`_forced_period` under base excitation: in absolute coordinates, the ground a massless node whose
    motion y = Y0 cos(omega t) is imposed step by step (the connector's kernel: each step moves it to y at the
    step's end), every element to the ground attached to it (it sees x_j - y = z_j, as in the balance). The state
    in and out is relative (z = x - y, z' = x' - y'): the multipliers are those of the relative motion."""
    from ..network import kernels

    system = balance.system
    network = system.network
    base = system.n
    elements = tuple(dataclasses.replace(e, between=tuple(base if end < 0 else end for end in e.between))
                     for e in network.elements)
    model = dataclasses.replace(network, nodes=network.nodes + ("base of the support",),
                                mass=np.append(network.mass, 0.0), x0=np.append(network.x0, 0.0),
                                v0=np.append(network.v0, 0.0), elements=elements, load_node=base).compile()
    h = 2.0 * math.pi / omega / steps
    Y0 = balance.base_amplitude
    path = Y0 * np.cos(omega * h * np.arange(1, steps + 1))
    massive = system.massive
    work = kernels.workspace(base + 1, len(elements))
    account, dissipated = np.zeros(3), np.zeros(len(elements))  # as the connector passes them (one compile)

    def run(x, v):
        x_all = np.append(x, 0.0) + Y0  # y(0) = Y0, y'(0) = 0
        v_all = np.append(v, 0.0)
        u_all = np.array(u, dtype=float)
        piece = np.zeros(len(elements), dtype=np.int64)
        for step in range(steps):
            status, _ = kernels.move_node(model, x_all, v_all, u_all, piece, work, account, dissipated, base,
                                          float(path[step]), 1, h, 0.0)
            if status < 0:
                from ..stepping import ElementError

                raise ElementError(f"{system.source}: a step of the stability check failed at f = "
                                   f"{omega / (2 * math.pi)!r} Hz")
        return np.concatenate((x_all[massive] - Y0, v_all[massive]))  # y(T) = Y0, y'(T) = 0

    return run


def forced_scene(balance, omega, solver):
    """The network of ``balance`` under its force at ``omega`` as a scene the network steppers run: F0 cos(omega t)
    on the load's node; base excitation (in relative coordinates, see ``harmonic_balance.py``): m Y0 omega^2
    cos(omega t) on the one node with a mass (FrequencyError for several: the network's load acts on one node;
    the stability check imposes the base's motion instead, :func:`_based_period`)."""
    import dataclasses

    from ..loads import HarmonicLoad
    from ..network.model import NetworkScene
    from . import FrequencyError

    system = balance.system
    network = system.network
    if balance.base_amplitude is None:
        amplitude = balance.force_amplitude
    else:
        if len(system.massive) != 1:
            raise FrequencyError(f"{system.source}: base excitation as a force is integrated for one node with "
                                 f"a mass (here {len(system.massive)}): the network's load acts on one node")
        node = system.massive[0]
        network = dataclasses.replace(network, load_node=node)
        amplitude = float(system.mass[node]) * balance.base_amplitude * omega * omega
    return NetworkScene(system.name, network, HarmonicLoad(amplitude, omega), solver, system.source)


def run_periods(balance, omega, state, periods: int, steps: int) -> tuple:
    """Integrate ``balance``'s system under its force at ``omega`` (:func:`forced_scene`; base excitation: in
    relative coordinates) for ``periods`` periods of ``steps`` implicit steps from ``state`` (x, v, u) at t = 0
    (one compiled call per period): ``(x of the last period (steps, n), the state at the end)``. The reference
    the tests and the benchmark hold the harmonic balance against."""
    from ..network.driver import NetworkElement, loop_for, run_loop
    from ..scene_tables import Solver
    from ..stepping import ElementError

    system = balance.system
    period = 2.0 * math.pi / omega
    h = period / steps
    scene = forced_scene(balance, omega, Solver("implicit", h, period, h))
    runner = NetworkElement(scene, "implicit", h)
    x, v, u = (np.array(a, dtype=float) for a in state)
    piece = runner.piece.copy()
    piece[:] = 0
    out = np.empty((steps, 2 * system.n + 2))
    load = scene.load.compile()
    for number in range(periods):
        taken, _ = run_loop(loop_for("implicit"), runner.model, load, x, v, u, piece, 0.0, number * steps, h, 1,
                            out, None, runner.account, None, runner.dissipated, None, runner.work)
        if taken < steps:
            raise ElementError(f"{system.source}: a step failed at f = {omega / (2 * math.pi)!r} Hz")
    return out[:, 0:2 * system.n:2].copy(), (x, v, u)
