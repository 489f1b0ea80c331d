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


def _log_ticks(axis) -> None:
    """A log axis's minor ticks at 2 and 5 of each decade (labelled where fewer than two decades show): matplotlib's
    default labels 2, 3, 4 and 6 there, which overlap on a narrow figure."""
    from matplotlib.ticker import LogFormatterSciNotation, LogLocator

    axis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))
    axis.set_minor_formatter(LogFormatterSciNotation(labelOnlyBase=False, minor_thresholds=(2, 0.5)))


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
        phase_axes.plot(f, np.degrees(_unwrapped(response.phase[rows][order])), marker + style, ms=4, lw=1,
                        label=f"sweep {direction}")
    if lines:
        fine = np.linspace(float(response.frequency.min()), float(response.frequency.max()), 400)
        for name, values in linear_responses(scene, response.force_amplitude, fine).items():
            amplitude_axes.plot(fine, values, ":", lw=1, label=name)
    amplitude_axes.set_yscale("log")
    _log_ticks(amplitude_axes.yaxis)
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


def _unwrapped(phase: np.ndarray) -> np.ndarray:
    """``phase`` (radians, in order along a curve) without its jumps of 2 pi across +-pi; a point without a
    phase (NaN) stays one and does not break the rest."""
    out = np.array(phase, dtype=float)
    finite = np.isfinite(out)
    out[finite] = np.unwrap(out[finite])
    return out


def draw_curve(curves, axes, backbone=None) -> None:
    """Draw the harmonic balance's curve (a :class:`curve.Curve`, or several: one colour each, labelled by its
    amplitude) on ``axes`` (two: amplitude, phase against the frequency): stable parts solid, unstable parts
    dashed, folds marked; ``backbone`` (a :class:`modes.Backbone`) over the amplitudes, with the response
    synthesised from it (``modes.synthesis``, under a force) dotted."""
    curves = list(curves) if isinstance(curves, (list, tuple)) else [curves]
    amplitude_axes, phase_axes = axes
    several = len(curves) > 1
    for index, curve in enumerate(curves):
        color = f"C{index % 10}" if several else "C0"
        f, stable = curve.frequency, curve.stable.tolist()  # (None where not computed: a masked entry)
        style = {True: "-", False: "--", None: ":"}
        # the phase along the curve without its jumps of 360 degrees across +-180 (as a Bode plot draws it)
        for ax, values in ((amplitude_axes, curve.amplitude), (phase_axes, np.degrees(_unwrapped(curve.phase)))):
            start = 0
            for end in range(1, f.size + 1):
                if end == f.size or stable[end] != stable[start]:
                    stop = min(end + 1, f.size)  # join the pieces
                    ax.plot(f[start:stop], values[start:stop], style[stable[start]], color=color, lw=1.2,
                            label=None)
                    start = end
            folds = curve.folds
            if folds.size:
                ax.plot(f[folds], values[folds], "o", color="C3", ms=5, label="fold" if index == 0 else None)
        if several:
            amplitude_axes.plot([], [], "-", color=color, label=_excitation(curve))
    first = curves[0]
    if several:
        amplitude_axes.plot([], [], "--", color="0.4", label="unstable")
    else:
        amplitude_axes.plot([], [], "-", color="C0", label=f"stable ({_how(first)})")
        amplitude_axes.plot([], [], "--", color="C0", label="unstable")
    if any(None in curve.stable.tolist() for curve in curves):
        amplitude_axes.plot([], [], ":", color="0.4", label="stability not computed")
    if backbone is not None:
        from .modes import synthesis

        # several points at one amplitude (a backbone that turns back there, by shooting): points, no line through
        # them in the order asked, and no synthesis (it needs one point per amplitude)
        single = np.unique(backbone.amplitude).size == backbone.amplitude.size
        amplitude_axes.plot(backbone.frequency, backbone.amplitude, "-" if single else "o", ms=3,
                            color="C2" if not several else "k", lw=1, label=f"backbone, mode {backbone.mode}")
        for curve in curves:
            if single and backbone.node == curve.node and curve.base_amplitude is None:
                f_s, a_s = synthesis(backbone, curve.force_amplitude, curve.load_node)
                inside = (f_s >= curve.frequency.min()) & (f_s <= curve.frequency.max())
                amplitude_axes.plot(f_s[inside], a_s[inside], ":", color="C2" if not several else "k", lw=1,
                                    label="single-mode synthesis" if curve is curves[0] else None)
    amplitude_axes.set_yscale("log")
    _log_ticks(amplitude_axes.yaxis)
    amplitude_axes.set_xlabel("frequency f (Hz)")
    amplitude_axes.set_ylabel(f"amplitude of x_{first.node} (m)")
    amplitude_axes.set_title(_how(first) if several else f"{first.method}, {_excitation(first)}")
    phase_axes.set_xlabel("frequency f (Hz)")
    phase_axes.set_ylabel("phase of x against " + ("the base's motion" if first.base_amplitude is not None
                                                   else "F") + " (degrees)")
    phase_axes.set_title("phase")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:  # the phase panel has labels only where something is drawn over
            ax.legend(fontsize=8)


def _how(curve) -> str:
    """How the curve was found, for a title: harmonic balance with its H, or shooting on the exact motion (on its
    Taylor series where the forces are not linear between events)."""
    if curve.method == "harmonic balance":
        return f"harmonic balance (H = {curve.harmonics})"
    return f"{curve.method} on the {curve.orbit}"


def _excitation(curve) -> str:
    if curve.base_amplitude is not None:
        return f"base Y0 = {curve.base_amplitude:g} m"
    return f"F0 = {curve.force_amplitude:g} N"


def plot_curve(curves, scene, path: str, backbone=None) -> None:
    """Write the figure of :func:`draw_curve` (one curve or several) to ``path``."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    draw_curve(curves, axes, backbone)
    method = (curves[0] if isinstance(curves, (list, tuple)) else curves).method
    fig.suptitle(f"{scene.name}: forced response by {method}")
    save_figure(fig, path)


def plot_backbone(backbone, scene, path: str) -> None:
    """Write the backbone (frequency and damping ratio against the amplitude) to ``path``."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    # several points at one amplitude (a backbone that turns back there): points only, no line in the order asked
    style = "o-" if np.unique(backbone.amplitude).size == backbone.amplitude.size else "o"
    axes[0].semilogy(backbone.frequency, backbone.amplitude, style, ms=4, lw=1)
    axes[0].set_xlabel("frequency f (Hz)")
    axes[0].set_ylabel(f"amplitude of x_{backbone.node} (m)")
    how = "shooting on the exact motion" if backbone.harmonics is None else f"H = {backbone.harmonics}"
    axes[0].set_title(f"backbone of mode {backbone.mode} ({how})")
    axes[1].semilogx(backbone.amplitude, backbone.damping_ratio, style, ms=4, lw=1)
    axes[1].set_xlabel(f"amplitude of x_{backbone.node} (m)")
    axes[1].set_ylabel("damping ratio")
    axes[1].set_title("modal damping")
    _log_ticks(axes[0].yaxis)
    _log_ticks(axes[1].xaxis)
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    fig.suptitle(f"{scene.name}: nonlinear mode by EPMC")
    save_figure(fig, path)
