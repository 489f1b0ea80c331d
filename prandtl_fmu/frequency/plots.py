"""Figures of the frequency domain: K(A) and the loss factor against A; the frequency response by sweep."""
from __future__ import annotations

import math

import numpy as np

from ..plots import save_figure
from .closed_forms import closed_form


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_description(description, scene, axes, label: str = "computed", closed: bool = True) -> None:
    """Draw K(A) (log-log) on ``axes[0]`` and the loss factor against A (log A) on ``axes[1]``, with the closed
    forms (``closed_forms.py``) over them where the scene has them, on amplitudes between the computed ones."""
    A = description.amplitude
    stiffness_axes, loss_axes = axes
    stiffness_axes.loglog(A, description.stiffness, "o", ms=4, label=label)
    positive = description.loss_factor > 0
    loss_axes.semilogx(A, description.loss_factor, "o", ms=4, label=label)
    if closed:
        fine = np.geomspace(float(A.min()), float(A.max()), 200) if A.size > 1 else A
        forms = closed_form(scene, fine, description.frequency)
        if forms is not None:
            K, D = forms
            stiffness_axes.loglog(fine, K, "-", lw=1, label="closed form")
            loss_axes.semilogx(fine, D / (math.pi * K * fine**2), "-", lw=1, label="closed form")
    stiffness_axes.set_xlabel("amplitude A (m)")
    stiffness_axes.set_ylabel("K(A) (N/m)")
    stiffness_axes.set_title("effective stiffness (first harmonic)")
    loss_axes.set_xlabel("amplitude A (m)")
    loss_axes.set_ylabel("loss factor D / (pi K A^2)")
    loss_axes.set_title("loss factor")
    if np.any(positive) and np.all(description.loss_factor >= 0):
        loss_axes.set_ylim(bottom=0)
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)


def plot_description(description, scene, path: str) -> None:
    """Write the figure of :func:`draw_description` to ``path``."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    draw_description(description, scene, axes)
    rate = f", f = {description.frequency:g} Hz" if description.frequency is not None else ""
    fig.suptitle(f"{scene.name}: describing function{rate}")
    save_figure(fig, path)


def linear_responses(scene, force_amplitude: float, frequencies) -> dict:
    """The linear responses |X| = F0 / |K - m omega^2 + i c omega| of the mass with every branch sticking
    (K = k0 + sum k_i) and with every branch slipping (K = k0), for reference lines (where they exist: a
    discrete set of branches or none; no cubic spring)."""
    f = np.asarray(frequencies, dtype=float)
    omega = 2.0 * math.pi * f
    k0 = scene.spring.k0 if scene.spring is not None else 0.0
    c = scene.damper.c if scene.damper is not None else 0.0
    m = scene.mass.m
    lines = {}
    if scene.cubic is not None:
        return lines
    stuck = k0 + (scene.branches.stiffness_sum if scene.branches is not None else 0.0)
    lines["all branches sticking"] = force_amplitude / np.abs(stuck - m * omega**2 + 1j * c * omega)
    if scene.branches is not None and (k0 > 0 or c > 0):
        with np.errstate(divide="ignore"):
            lines["all branches slipping (k0 and c only)"] = force_amplitude / np.abs(k0 - m * omega**2
                                                                                      + 1j * c * omega)
    return lines


def draw_response(response, scene, axes, lines: bool = True) -> None:
    """Draw the amplitude (log) and the phase against the frequency on ``axes`` (two), one line per sweep,
    with the linear responses (:func:`linear_responses`) dashed."""
    amplitude_axes, phase_axes = axes
    markers = {"up": ("^", "-"), "down": ("v", "--")}
    sweeps = np.array(response.sweep)
    for direction in ("up", "down"):
        rows = sweeps == direction
        if not np.any(rows):
            continue
        order = np.argsort(response.frequency[rows])
        marker, style = markers[direction]
        f = response.frequency[rows][order]
        amplitude_axes.plot(f, response.amplitude[rows][order], marker + style, ms=4, lw=1,
                            label=f"sweep {direction}")
        phase_axes.plot(f, np.degrees(response.phase[rows][order]), marker + style, ms=4, lw=1,
                        label=f"sweep {direction}")
    if lines:
        fine = np.linspace(float(response.frequency.min()), float(response.frequency.max()), 400)
        for name, values in linear_responses(scene, response.force_amplitude, fine).items():
            amplitude_axes.plot(fine, values, ":", lw=1, label=name)
    amplitude_axes.set_yscale("log")
    amplitude_axes.set_xlabel("frequency f (Hz)")
    amplitude_axes.set_ylabel("amplitude of x (m)")
    amplitude_axes.set_title(f"first harmonic of x, F0 = {response.force_amplitude:g} N")
    phase_axes.set_xlabel("frequency f (Hz)")
    phase_axes.set_ylabel("phase of x against F (degrees)")
    phase_axes.set_title("phase")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)


def plot_response(response, scene, path: str) -> None:
    """Write the figure of :func:`draw_response` to ``path``."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    draw_response(response, scene, axes)
    fig.suptitle(f"{scene.name}: frequency response ({response.stepper})")
    save_figure(fig, path)
