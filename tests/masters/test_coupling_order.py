"""The connector example coupled at second order (issue 61, item 5(b)): a point mass on the bushing connector in a
Jacobi and a Gauss-Seidel loop written here over FMPy's low-level API (FMU2Slave), with and without the derivatives
the FMUs exchange, against the same system as one element solved by the exact stepper.

The system is docs/connector.md's example, m x'' = A cos(omega t) - force(x, v), with the mass as a native element
FMU (its input F = A cos(omega t) - force, set by the master) and the bushing as the native connector FMU. At each
communication point tc the master reads the mass's x, v, sets them on the connector and reads its force there
(direct feedthrough), sets F on the mass and, with derivatives:

* reads the mass's output derivatives (x: v, a; v: a, a') and sets them on the connector as its input derivatives
  (over the step it follows x + v (t - tc) + a (t - tc)^2 / 2, v the same with a, a');
* Jacobi: sets F' = -A omega sin(omega tc) - force' and F'' = -A omega^2 cos(omega tc) - force'' on the mass,
  force' and force'' the connector's output derivatives at its state as the last step left it (its path's end: what
  a master reads after a step), along the mass's motion set as its input derivatives (K_t v + c a and K_t a + c a'),
  then steps both. Read instead at the new inputs' preview they are first order: the preview moves the connector
  back from its path's end to the mass's x (the path overshoots by O(H^3)), which takes the branches that were
  sliding just off their thresholds, and the one-sided tangent counts them as sticking for the motion ahead, though
  they slide again after O(H^3): a switch in nearly every step while the joint slips;
* Gauss-Seidel: steps the connector first (its force at tc + H, at the end of the path it followed), then sets on the
  mass the slope F' of F between tc and tc + H, and steps the mass.

Without derivatives both FMUs hold their inputs over a step. Run as a script it prints the table of docs/connector.md:

    python -m tests.masters.test_coupling_order
"""
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "cosim" / "connector"
AMPLITUDE, OMEGA = 0.45, 0.5  # the example's harmonic force (bushing-with-mass.toml's [load])
MASS = """name = "point-mass"

[mass]
m = 1.0

[solver]
stepper = "verlet"
step = 1e-4
stop_time = 40.0
output_interval = 0.01
"""
STEPS = (0.1, 0.05, 0.025, 0.0125, 0.00625)
STOP_TIME = 20.0
COMPARED_EVERY = 0.1  # s: the instants every communication step of STEPS reaches


def build(folder: Path) -> dict:
    """The native mass and bushing FMUs in ``folder``."""
    from prandtl_fmu.fmu.build import build_fmu

    (folder / "point-mass.toml").write_text(MASS)
    return {"mass": build_fmu(folder / "point-mass.toml", folder / "point-mass.fmu", runtime="native"),
            "bushing": build_fmu(EXAMPLE / "bushing.toml", folder / "bushing.fmu", runtime="native")}


def reference(stop_time: float) -> np.ndarray:
    """x of bushing-with-mass.toml (the exact stepper) every COMPARED_EVERY s from 0 to ``stop_time``."""
    from prandtl_fmu import load_scene, simulate

    scene = load_scene(EXAMPLE / "bushing-with-mass.toml")
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, stop_time=stop_time,
                                                                  output_interval=COMPARED_EVERY))
    return np.asarray(simulate(scene).x)


def coupled(fmus: dict, step: float, stop_time: float, scheme: str, derivatives: bool) -> np.ndarray:
    """x of the mass every COMPARED_EVERY s from 0 to ``stop_time``, coupled by ``scheme`` ("jacobi" or
    "gauss-seidel") at communication step ``step``, with or without ``derivatives`` (see the module)."""
    from tests.fmu_tools import Slave

    mass, bushing = Slave(fmus["mass"], name="mass"), Slave(fmus["bushing"], name="bushing")
    m, b = mass.vr, bushing.vr
    count, every = round(stop_time / step), round(COMPARED_EVERY / step)
    found = []
    try:
        for j in range(count + 1):
            tc = j * step
            x, v = mass.fmu.getReal([m["x"], m["v"]])
            if j % every == 0:
                found.append(x)
            if j == count:
                break
            if derivatives and scheme == "jacobi":  # force' and force'' at the connector's own state, as the step
                # left it (its path's end), along the mass's motion: its output derivatives with (v, a), (a, a') set
                a, jerk = mass.fmu.getRealOutputDerivatives([m["v"], m["v"]], [1, 2])
                bushing.fmu.setRealInputDerivatives([b["x"], b["x"], b["v"], b["v"]], [1, 2, 1, 2], [v, a, a, jerk])
                rate, bend = bushing.fmu.getRealOutputDerivatives([b["force"], b["force"]], [1, 2])
            bushing.fmu.setReal([b["x"], b["v"]], [x, v])
            force = bushing.fmu.getReal([b["force"]])[0]
            load = AMPLITUDE * math.cos(OMEGA * tc) - force
            mass.fmu.setReal([m["F"]], [load])
            if derivatives:
                a, jerk = mass.fmu.getRealOutputDerivatives([m["v"], m["v"]], [1, 2])
                bushing.fmu.setRealInputDerivatives([b["x"], b["x"], b["v"], b["v"]], [1, 2, 1, 2], [v, a, a, jerk])
                if scheme == "jacobi":
                    slope = -AMPLITUDE * OMEGA * math.sin(OMEGA * tc) - rate
                    curvature = -AMPLITUDE * OMEGA ** 2 * math.cos(OMEGA * tc) - bend
                else:
                    bushing.fmu.doStep(tc, step)
                    ahead = AMPLITUDE * math.cos(OMEGA * (tc + step)) - bushing.fmu.getReal([b["force"]])[0]
                    slope = (ahead - load) / step
                if scheme == "jacobi":
                    mass.fmu.setRealInputDerivatives([m["F"], m["F"]], [1, 2], [slope, curvature])
                else:
                    mass.fmu.setRealInputDerivatives([m["F"]], [1], [slope])
                mass.fmu.doStep(tc, step)
                if scheme == "jacobi":
                    bushing.fmu.doStep(tc, step)
            else:
                mass.fmu.doStep(tc, step)
                bushing.fmu.doStep(tc, step)
    finally:
        mass.close()
        bushing.close()
    return np.array(found)


def errors(fmus: dict, stop_time: float) -> dict:
    """{(scheme, derivatives): [max |x - x_ref| at each of STEPS]} over ``stop_time`` s."""
    wanted = reference(stop_time)
    return {(scheme, derivatives): [float(np.max(np.abs(coupled(fmus, step, stop_time, scheme, derivatives) - wanted)))
                                    for step in STEPS]
            for scheme in ("jacobi", "gauss-seidel") for derivatives in (False, True)}


def orders(values) -> list:
    """The order between each pair of successive STEPS (halved)."""
    return [math.log2(coarse / fine) for coarse, fine in zip(values[:-1], values[1:])]


def fitted_order(values) -> float:
    """The slope of log(error) against log(H), least squares over STEPS."""
    return float(np.polyfit(np.log(STEPS), np.log(values), 1)[0])


@pytest.mark.slow
def test_the_connector_example_converges_at_second_order_with_derivatives_exchanged(tmp_path):
    """Over 20 s at H = 0.1 ... 0.00625 s: the error of x falls at order ~1 with the inputs held (each halving and
    the fit), at a fitted order >= 1.8 with the derivatives exchanged, in both loops; with them it is smaller at
    every H."""
    found = errors(build(tmp_path), STOP_TIME)
    for scheme in ("jacobi", "gauss-seidel"):
        held, exchanged = found[scheme, False], found[scheme, True]
        assert all(0.8 < order < 1.3 for order in orders(held)), (scheme, held)
        assert 0.9 < fitted_order(held) < 1.2, (scheme, held)
        assert fitted_order(exchanged) >= 1.8 and min(orders(exchanged)) > 1.6, (scheme, exchanged)
        assert all(a < b / 10 for a, b in zip(exchanged, held)), (scheme, exchanged, held)


def main() -> None:
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        found = errors(build(Path(folder)), STOP_TIME)
    print("| H (s) | Jacobi, held (m) | Jacobi, derivatives (m) | order | Gauss-Seidel, held (m) "
          "| Gauss-Seidel, derivatives (m) | order |")
    print("|---|---|---|---|---|---|---|")
    for i, step in enumerate(STEPS):
        cells = [f"{step:g}"]
        for scheme in ("jacobi", "gauss-seidel"):
            held, exchanged = found[scheme, False], found[scheme, True]
            cells += [f"{held[i]:.2e}", f"{exchanged[i]:.2e}", f"{orders(exchanged)[i - 1]:.2f}" if i else ""]
        print("| " + " | ".join(cells) + " |")
    cells = ["fitted order"]
    for scheme in ("jacobi", "gauss-seidel"):
        cells += [f"{fitted_order(found[scheme, False]):.2f}", f"{fitted_order(found[scheme, True]):.2f}", ""]
    print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    sys.exit(main())
