"""The benchmark's problem: the paper's section 8 scene (Bastien & Schatzman, M2AN 2002) with n branches, and
the paper's Table 1 (the order alpha, the constant C and the correlation r of eps(h) it printed, and the
protocol that made it), which the measured tables are set beside (``table1.py``, ``work_precision.py``).

m = 1 kg, k0 = 0, the spectrum k(s) = 1, eta(s) = s + 0.1 on s in [0, 1] (k_i = 1/n, eta_i = 0.1 + i/n), F =
0.45 cos(0.5 t) N; the error of a run is measured on the output grid of :data:`OUTPUT` (s).
"""
from __future__ import annotations

import os
from dataclasses import replace

from ..effects import ContinuousBranches

PAPER_TABLE_1 = {  # (q, n): (alpha, C) as printed in Bastien & Schatzman (2002), Table 1
    ("inf", 3): (1.00162, 0.71734), ("inf", 10): (1.00166, 0.75184), ("inf", 100): (1.00177, 0.83276),
    ("inf", 700): (1.00125, 0.83106), ("inf", 1500): (1.00164, 0.83188),
    ("2", 3): (1.00165, 0.75175), ("2", 10): (1.00278, 0.85304), ("2", 100): (1.00196, 1.34671),
    ("2", 700): (1.00215, 2.00740), ("2", 1500): (1.00215, 2.36276),
}
PAPER_CORRELATION = {  # (q, n): r, the correlation of the points (log h, log eps) printed beside them
    ("inf", 3): 0.999998, ("inf", 10): 0.999998, ("inf", 100): 0.999998, ("inf", 700): 0.999999,
    ("inf", 1500): 0.999998,
    ("2", 3): 0.999998, ("2", 10): 0.999996, ("2", 100): 0.999998, ("2", 700): 0.999998, ("2", 1500): 0.999998,
}
# Section 8's protocol: the n of Table 1 and of the figures 3-5, the horizon T (s), the steps of the figures'
# runs (N = 10^6, h = T / N), and Table 1's grid h_j = h_min^((R - j)/R) h_max^(j/R), j = 0..R
PAPER_NS = (3, 10, 100, 700, 1500)
PAPER_T = 500.0
PAPER_FIGURE_STEPS = 1_000_000
PAPER_GRID = dict(R=99, h_min=1e-6, h_max=1e-2)
OUTPUT = 0.1  # s: the output interval, the grid on which a run's error is measured


def paper_scene(n, stop_time: float, rule: str = "right"):
    """The paper's section 8 scene up to ``stop_time``, with n branches sampled from its spectrum k(s) = 1,
    eta(s) = s + 0.1 (by ``rule``: "right" is eq. 7.19), or the continuum itself for ``n=None``."""
    from ..scene import parse_scene

    root = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "paper-section-8.toml")
    if os.path.exists(root):
        with open(root) as fh:
            scene = parse_scene(fh.read(), root)
    else:  # installed without the repository: the same scene, written out
        scene = parse_scene(_PAPER_SCENE, "paper-section-8.toml")
    spectrum = ContinuousBranches.linear(1.0, 0.1, 1.1)
    branches = spectrum if n is None else spectrum.sample(n, rule)
    return replace(scene, branches=branches).with_solver(stop_time=stop_time, output_interval=OUTPUT)


_PAPER_SCENE = """
name = "paper-section-8"
[mass]
m = 1.0
[spring]
k0 = 0.0
[branches]
count = 100
k_total = 1.0
eta_range = [0.1, 1.1]
[load]
kind = "harmonic"
amplitude = 0.45
omega = 0.5
[solver]
stepper = "projected"
step = 1e-3
stop_time = 500.0
output_interval = 0.1
"""
