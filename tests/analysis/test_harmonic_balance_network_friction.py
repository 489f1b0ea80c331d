"""The forced response of a network with sliders (the chain on a support among them) by shooting on its motion,
event by event and exact between events (``frequency/network_orbit.py``, ``frequency/shooting.py``): a node on
a slider is Den Hartog's closed form, two masses that a slider locks together are one linear oscillator, random
networks and a chain keep their orbit under the implicit stepper (its first-order error halves with the step
towards it), stable points attract, two motions' difference contracts (why no point is unstable), the command
line end to end, and what is refused."""
import dataclasses
import math

import numpy as np
import pytest

from prandtl_fmu.cli import main
from prandtl_fmu.frequency import FrequencyError

from tests.analysis.test_describe_cli import read_csv
from tests.analysis.test_harmonic_balance_friction import non_stop_orbit


SOLVER = '[solver]\nstepper = "implicit"\nstep = 0.001\nstop_time = 1.0\noutput_interval = 0.01\n'


def network_text(nodes, mass, elements, load_node=None, name="net"):
    """TOML of a network: ``elements`` a list of (kind, between, {key: value})."""
    lines = [f'name = "{name}"', "[network]", "nodes = [" + ", ".join(f'"{n}"' for n in nodes) + "]",
             "mass = [" + ", ".join(repr(float(m)) for m in mass) + "]"]
    if load_node:
        lines.append(f'load_node = "{load_node}"')
    for kind, between, values in elements:
        lines += [f"[[network.{kind}]]", "between = [" + ", ".join(f'"{b}"' for b in between) + "]"]
        lines += [f"{key} = {float(value)!r}" for key, value in values.items()]
    return "\n".join(lines) + "\n" + SOLVER


def network(tmp_path, text, name="net.toml"):
    from prandtl_fmu.scene import load_scene

    path = tmp_path / name
    path.write_text(text)
    return load_scene(str(path))


ONE_NODE = network_text(["a"], [1.0], [("spring", ["a", "ground"], {"k": 1.0}),
                                       ("slider", ["a", "ground"], {"alpha": 0.1})])
TWO_MASSES = "networks/two-masses-slider"


def chain(n=4):
    """The chain on a support of scenes/networks/chain-dynamic.toml, shortened to n nodes."""
    return (f'name = "chain"\n[chain]\nn = {n}\nm = 0.1\nk = 1000.0\nalpha = 1.0\nc = 0.05\nk_wall = 1000.0\n' + SOLVER)


def periodic_state(scene, force, f, steps=256):
    from prandtl_fmu.frequency.shooting import NetworkShooting

    omega = 2 * math.pi * f
    shooting = NetworkShooting(scene, force, None, steps, 7, omega)
    return shooting, shooting.solve_at(omega), omega


@pytest.mark.slow
@pytest.mark.parametrize("base", [False, True])
def test_a_node_on_a_slider_is_den_hartogs_non_stop_motion(tmp_path, base):
    """A mass on a spring and a slider to the ground, above its resonance: every point's first harmonic is the
    closed-form orbit's to the tolerance asked (1e-7), stable; under base excitation Y0 cos(omega t) the same
    orbit in coordinates relative to the ground, under m Y0 omega^2 cos(omega t), plus Y0."""
    from prandtl_fmu.frequency.curve import harmonic_response

    scene = network(tmp_path, ONE_NODE)
    band = (1.3 / (2 * math.pi), 3.0 / (2 * math.pi))
    if base:
        curve = harmonic_response(scene, None, band, base_amplitude=0.5, tolerance=1e-7)
    else:
        curve = harmonic_response(scene, 1.0, band, tolerance=1e-7)
    assert len(curve.frequency) >= 2 and np.all(curve.stable) and curve.method == "shooting"
    for f, amplitude, phase in zip(curve.frequency, curve.amplitude, curve.phase):
        omega = 2 * math.pi * f
        X, phi, x, t = non_stop_orbit(1.0, 1.0, 0.1, 0.5 * omega * omega if base else 1.0, omega)
        first = complex(x @ (np.exp(-1j * omega * t) * 2.0 / t.size)) * np.exp(-1j * phi)
        if base:
            first += 0.5
        assert amplitude == pytest.approx(abs(first), rel=1e-7)
        assert phase == pytest.approx(np.angle(first), abs=1e-7)


# Den Hartog's bound along the springs' undamped mode, written out: the node alone on its spring (4 / pi of the
# slider's 0.1 N); the two masses' mode a alone (b's dashpot damps b's mode), held by the slider (2 N) and the
# branch (k eta = 1 N) between them
ONE_NODE_BOUND, ONE_NODE_NATURAL = 4 / math.pi * 0.1, 1 / (2 * math.pi)
TWO_MASSES_BOUND, TWO_MASSES_NATURAL = 4 / math.pi * (2.0 + 50.0 * 0.02), math.sqrt(100.0) / (2 * math.pi)


@pytest.mark.parametrize("case", ["one node", "two masses", "two masses, base"])
def test_a_resonance_that_friction_cannot_hold_is_refused_before_the_curve_starts(tmp_path, capsys, case):
    """Den Hartog: a mass on a spring and a slider forced beyond 4 / pi of the friction has no periodic state at
    its natural frequency (the amplitude grows without bound). So has any network on a mode of its springs that
    no dashpot damps, forced beyond 4 / pi of its sliders' and branches' forces along the mode. A curve over that
    frequency is refused before it starts (it used to climb the resonance for minutes), in one line that names
    the frequency, the force that would do and the bound; a hair below the bound is not refused there."""
    from prandtl_fmu.frequency.unbounded import refuse_unbounded
    from prandtl_fmu.scene import load_scene

    if case == "one node":
        path, bound, natural = tmp_path / "one.toml", ONE_NODE_BOUND, ONE_NODE_NATURAL
        path.write_text(ONE_NODE)
        scene = network(tmp_path, ONE_NODE)
    else:
        path, bound, natural = TWO_MASSES, TWO_MASSES_BOUND, TWO_MASSES_NATURAL
        scene = load_scene(TWO_MASSES)
    band = (0.5 * 2 * math.pi * natural, 2 * 2 * math.pi * natural)  # rad/s
    if case.endswith("base"):  # m_a Y0 omega^2 on the mode (b's share is 0)
        option, limit = "--base-amplitude", bound / (2 * math.pi * natural) ** 2
        refuse_unbounded(scene, None, 0.99 * limit, *band)
    else:
        option, limit = "--force-amplitude", bound
        refuse_unbounded(scene, 0.99 * limit, None, *band)
    refuse_unbounded(scene, 10 * bound, None, 1.01 * 2 * math.pi * natural, band[1])  # the resonance left out
    out = tmp_path / "curve.csv"
    assert main(["describe", str(path), option, repr(1.01 * limit), "--frequencies",
                 f"{0.5 * natural!r},{2 * natural!r}", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and not out.exists(), err
    assert f"no periodic state at f = {natural:.6g} Hz" in err and "Den Hartog" in err, err
    assert f"below {limit:.6g} " in err, err


@pytest.mark.parametrize("base", [False, True])
def test_den_hartog_s_bound_along_coupled_modes_is_the_generalized_eigenproblem_s(tmp_path, base):
    """Two unequal masses coupled by a spring and a slider between them, a slider from b to the ground, no dashpot:
    both modes of the springs are coupled and undamped. For each, the bound written out from scipy's K phi =
    omega^2 M phi: the force that the sliders hold is 4 / pi (0.2 |phi_a - phi_b| + 0.1 |phi_b|) over the force's
    share |phi_a| (at a), or over |phi' M 1| omega^2 under base excitation. 1.01 of it is refused with that value
    named, 0.99 of it is not (a shape not scaled by the masses, or an element's far end taken with the wrong sign,
    moves the bound by far more than 1 %)."""
    from scipy.linalg import eigh

    from prandtl_fmu.frequency import FrequencyError
    from prandtl_fmu.frequency.unbounded import refuse_unbounded

    text = network_text(["a", "b"], [1.0, 3.0], [
        ("spring", ["a", "ground"], {"k": 2.0}), ("spring", ["b", "ground"], {"k": 5.0}),
        ("spring", ["a", "b"], {"k": 1.0}), ("slider", ["a", "b"], {"alpha": 0.2}),
        ("slider", ["b", "ground"], {"alpha": 0.1})], load_node="a")
    scene = network(tmp_path, text)
    M, K = np.diag([1.0, 3.0]), np.array([[3.0, -1.0], [-1.0, 6.0]])
    values, shapes = eigh(K, M)
    assert np.all(np.abs(shapes[0]) > 0.1) and np.all(np.abs(shapes[1]) > 0.1)  # coupled: both nodes move
    for value, phi in zip(values, shapes.T):
        omega = math.sqrt(value)
        hold = 4 / math.pi * (0.2 * abs(phi[0] - phi[1]) + 0.1 * abs(phi[1]))
        limit = hold / (abs(phi @ M @ np.ones(2)) * value if base else abs(phi[0]))
        band = (0.97 * omega, 1.03 * omega)  # this mode alone (the other is 1.9 times away)
        forcing = (lambda amount: (None, amount)) if base else (lambda amount: (amount, None))
        refuse_unbounded(scene, *forcing(0.99 * limit), *band)
        with pytest.raises(FrequencyError, match=f"below {limit:.6g} ") as refusal:
            refuse_unbounded(scene, *forcing(1.01 * limit), *band)
        assert f"f = {omega / (2 * math.pi):.6g} Hz" in str(refusal.value)


def test_an_undamped_linear_resonance_is_refused_as_such(tmp_path, capsys):
    """A mass on a spring alone over its resonance: refused in one line that says nothing bounds the mode (it
    offered a force 'below 0 N', held by sliders that are not there), under a force and under base excitation."""
    path = tmp_path / "linear.toml"
    path.write_text(network_text(["a"], [1.0], [("spring", ["a", "ground"], {"k": 1.0})], load_node="a"))
    for option in ("--force-amplitude", "--base-amplitude"):
        assert main(["describe", str(path), option, "0.1", "--frequencies", "0.1,0.3"]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "an undamped linear resonance" in err, err
        assert " 0 N" not in err and "f = 0.159155 Hz" in err, err


def test_a_cubic_joint_the_mode_leaves_alone_does_not_stop_den_hartog_s_bound(tmp_path, capsys):
    """Two equal masses on equal springs to the ground, joined by a cubic spring, a branch and a dashpot: the
    in-phase mode (1, 1) at 1 / (2 pi) Hz stretches none of them (d . phi = 0), so their forces project to 0 on
    it and only the branch to the ground (k eta = 0.02 N, |phi_a| = 1) holds it: the force 0.1 N > 4 / pi 0.02
    drives it without bound. The cubic spring stopped the check (its force is not bounded), and the curve climbed
    until its bound of points; now refused at once, where 0.99 of the bound passes. A cubic spring the mode
    stretches (a to the ground) still stops the check: nothing refused."""
    from prandtl_fmu.frequency import FrequencyError
    from prandtl_fmu.frequency.unbounded import refuse_unbounded

    joint = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
             ("cubic", ["a", "b"], {"k3": 4.0}), ("branch", ["a", "b"], {"k": 2.0, "eta": 0.1}),
             ("dashpot", ["a", "b"], {"c": 0.1}), ("branch", ["a", "ground"], {"k": 0.2, "eta": 0.1})]
    scene = network(tmp_path, network_text(["a", "b"], [1.0, 1.0], joint, load_node="a"))
    band = (0.9, 1.1)  # rad/s: the in-phase mode at 1 alone (the other at sqrt(3) is far)
    limit = 4 / math.pi * 0.02
    refuse_unbounded(scene, 0.99 * limit, None, *band)
    with pytest.raises(FrequencyError, match=f"below {limit:.6g} "):
        refuse_unbounded(scene, 1.01 * limit, None, *band)
    stretched = network(tmp_path, network_text(["a", "b"], [1.0, 1.0], joint + [
        ("cubic", ["a", "ground"], {"k3": 1.0})], load_node="a"), name="stretched.toml")
    refuse_unbounded(stretched, 10 * limit, None, *band)
    path = tmp_path / "joint.toml"
    path.write_text(network_text(["a", "b"], [1.0, 1.0], joint, load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.1,0.3"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "f = 0.159155 Hz" in err, err


def test_a_mode_that_stretches_only_the_joint_s_elements_at_rounding_is_an_undamped_linear_resonance(tmp_path,
                                                                                                      capsys):
    """The cubic joint above with a slider in it and no branch to the ground: the in-phase mode stretches the
    slider and the branch by rounding only (1e-16 of the shape, from the null space of the cubic spring's row),
    which made a bound of 2e-16 N and offered 'a force amplitude below 2.12e-16 N'. Nothing bounded holds the
    mode: refused as an undamped linear resonance, with no force offered."""
    joint = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
             ("cubic", ["a", "b"], {"k3": 4.0}), ("branch", ["a", "b"], {"k": 2.0, "eta": 0.1}),
             ("slider", ["a", "b"], {"alpha": 0.3}), ("dashpot", ["a", "b"], {"c": 0.1})]
    path = tmp_path / "joint.toml"
    path.write_text(network_text(["a", "b"], [1.0, 1.0], joint, load_node="a"))
    assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.1,0.3"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "an undamped linear resonance" in err, err
    assert "f = 0.159155 Hz" in err and " N (4 / pi" not in err and "below" not in err, err


def test_a_joint_whose_cubic_spring_holds_two_masses_together_at_large_amplitude_is_not_refused(tmp_path):
    """Mass a on a spring (1 N/m) and a slider (0.15 N) to the ground, b joined to a by a spring, a branch, a
    slider, a hardening cubic spring and a dashpot. At large amplitude the cubic spring holds the two together,
    and the mode left, a = b at sqrt(1 / 2) rad/s, has no dashpot on it and only the ground's slider along it:
    0.2 N drives it past Den Hartog's 4 / pi 0.15 = 0.19 N, and a motion that large grows without bound. That
    does not make the curve climb: at that frequency, from rest, the implicit stepper settles on an orbit of
    0.43 m, and the curve passes it near there. A check before the curve starts that refused this (tried: the
    same two masses without the ground's slider do climb, from 0.05 Hz, past 300 m) would refuse a curve that
    exists; the check refuses only where no periodic state exists at all."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.network.driver import simulate
    from prandtl_fmu.scene import load_scene

    joint = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["a", "b"], {"k": 0.5}),
             ("branch", ["b", "a"], {"k": 2.0, "eta": 0.1}), ("slider", ["a", "b"], {"alpha": 0.3}),
             ("cubic", ["a", "b"], {"k3": 4.0}), ("slider", ["ground", "a"], {"alpha": 0.15}),
             ("dashpot", ["a", "b"], {"c": 0.1})]
    text = network_text(["a", "b"], [1.0, 1.0], joint, load_node="a")
    omega = math.sqrt(0.5)
    curve = harmonic_response(network(tmp_path, text), 0.2, [0.05, 0.2], stability=False)
    assert curve.frequency[0] < omega / (2 * math.pi) < curve.frequency[-1]
    near = np.abs(curve.frequency - omega / (2 * math.pi)) < 0.01
    assert np.any(near) and np.all(curve.amplitude < 1.0), np.max(curve.amplitude)
    solver = (f'[load]\nkind = "harmonic"\namplitude = 0.2\nomega = {omega!r}\n[solver]\nstepper = "implicit"\n'
              'step = 0.01\noutput_interval = 0.05\nstop_time = 1800.0\n')
    run = simulate(load_scene(str(_written(tmp_path / "run.toml", text.replace(SOLVER, solver)))))
    period = 2 * math.pi / omega
    late = [float(np.max(np.abs(run.x[(run.time > (k - 1) * period) & (run.time <= k * period), 0])))
            for k in (100, 200)]
    assert late[1] == pytest.approx(late[0], rel=1e-3) and 0.3 < late[1] < 0.6, late
    assert np.max(curve.amplitude[near]) > 0.5 * late[1]


def _written(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize("masses", [2, 3])
def test_a_maxwell_node_the_mode_leaves_alone_does_not_hide_an_undamped_resonance(tmp_path, capsys, masses):
    """Equal masses a and b on equal springs (and, with three, a third mass c coupled to both, loaded), a
    slider and a Maxwell element written with its massless node p (a spring a-p, a dashpot p-b) between a and b,
    no other dashpot: the springs' mode with a = b stretches neither, nothing damps or holds it, and there is no
    periodic state at its frequency. Shooting takes p as a lever with a series dashpot (``series._maxwell``),
    whose range 1e200 counted as a bound: with d . phi at rounding (1e-16 on three masses), or any vector of the
    repeated mode of two, the check let the curve climb (past 5 minutes, a review's find). Now the lever counts
    as unbounded, the mode's vectors that leave it alone are checked, and the curve is refused at once."""
    nodes, mass = (["a", "b", "p"], [1.0, 1.0, 0.0]) if masses == 2 else (["a", "b", "c", "p"],
                                                                          [1.3, 1.3, 0.7, 0.0])
    elements = [("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["b", "ground"], {"k": 1.0}),
                ("slider", ["a", "b"], {"alpha": 0.05}), ("spring", ["a", "p"], {"k": 1.0}),
                ("dashpot", ["p", "b"], {"c": 0.5})]
    if masses == 3:
        elements += [("spring", ["c", "ground"], {"k": 0.5}), ("spring", ["a", "c"], {"k": 0.37}),
                     ("spring", ["b", "c"], {"k": 0.37})]
    path = tmp_path / "maxwell.toml"
    path.write_text(network_text(nodes, mass, elements, load_node="a" if masses == 2 else "c"))
    assert main(["describe", str(path), "--force-amplitude", "0.1", "--frequencies", "0.1,0.2"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "no periodic state at f = " in err, err
    assert "no dashpot acts on the springs' mode" in err, err


@pytest.mark.slow
@pytest.mark.parametrize("case", ["one node", "two masses"])
def test_just_below_den_hartog_s_bound_the_curve_passes_the_resonance(tmp_path, case):
    """At 0.99 of the bound the curve goes through the springs' natural frequency, its amplitude bounded: the
    bound is sharp, not a margin that refuses curves that exist."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.scene import load_scene

    if case == "one node":
        scene, bound, natural = network(tmp_path, ONE_NODE), ONE_NODE_BOUND, ONE_NODE_NATURAL
    else:
        scene, bound, natural = load_scene(TWO_MASSES), TWO_MASSES_BOUND, TWO_MASSES_NATURAL
    curve = harmonic_response(scene, 0.99 * bound, [0.5 * natural, 2 * natural], stability=False)
    assert curve.frequency[0] < natural < curve.frequency[-1] and np.all(np.diff(curve.frequency) > 0)
    assert np.all(np.isfinite(curve.amplitude)) and np.max(curve.amplitude) < 1e3 * 0.99 * bound


@pytest.mark.slow
def test_a_curve_past_its_bound_of_points_says_where_it_stopped(tmp_path, monkeypatch):
    """The continuation's bound of points (here lowered to 20): the refusal says the frequency and the
    first-harmonic amplitude at --node where the curve stopped, within the band."""
    import re

    from prandtl_fmu.frequency import continuation
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.scene import load_scene

    monkeypatch.setattr(continuation, "MAX_POINTS", 20)
    with pytest.raises(FrequencyError) as refused:
        harmonic_response(load_scene(TWO_MASSES), 3.5, [0.5, 3.0], stability=False, node="b")
    said = re.search(r"within 20 points \(at f = (\S+) Hz, first-harmonic amplitude (\S+) m at node b",
                     str(refused.value))
    assert said, refused.value
    assert 0.5 < float(said.group(1)) < 3.0 and float(said.group(2)) > 0


@pytest.mark.slow
def test_two_masses_a_slider_locks_together_are_one_linear_oscillator():
    """Under a small force the slider between the two masses never slips (its tension stays below alpha): both
    move as one mass m_a + m_b on the springs and the dashpot to the ground, in closed form."""
    from prandtl_fmu.frequency.curve import harmonic_response
    from prandtl_fmu.scene import load_scene

    curve = harmonic_response(load_scene(TWO_MASSES), 0.05, [0.3, 1.2], tolerance=1e-9)
    omega = 2 * math.pi * curve.frequency
    locked = 0.05 / (500.0 - 3.0 * omega**2 + 0.5j * omega)
    assert np.allclose(curve.amplitude, np.abs(locked), rtol=1e-9, atol=0)
    assert np.allclose(curve.amplitudes["b"], np.abs(locked), rtol=1e-9, atol=0)
    assert np.allclose(curve.phase, np.angle(locked), rtol=0, atol=1e-9)
    assert np.all(curve.stable)


def _implicit_runs(scene, shooting, s, omega, force, steps, periods=1):
    """``(orbit, runs)``: the orbit's x over a period (n, M) and, for each count of steps per period, the
    implicit stepper's x from the periodic state over the last of ``periods`` periods, at the orbit's samples."""
    from prandtl_fmu.loads import HarmonicLoad
    from prandtl_fmu.network.driver import simulate
    from prandtl_fmu.scene_tables import Solver

    n = scene.network.n
    T = 2 * math.pi / omega
    orbit = shooting.samples(s, omega)  # (n, M)
    M = orbit.shape[1]
    branches = iter(s[2 * n:])
    elements = tuple(dataclasses.replace(e, u0=float(next(branches))) if e.kind == "branch" else e
                     for e in scene.network.elements)
    start = dataclasses.replace(scene.network, x0=np.array(s[:n]), v0=np.array(s[n:2 * n]) * shooting.reference,
                                elements=elements)
    runs = []
    for count in steps:
        run = dataclasses.replace(scene, network=start, load=HarmonicLoad(force, omega),
                                  solver=Solver("implicit", T / count, periods * T, T / M))
        runs.append(simulate(run, progress=False).x[-M - 1:-1].T)
    return orbit, runs


def _implicit_errors(scene, shooting, s, omega, force, periods=1):
    """The implicit stepper's motion from the periodic state at T / 4096 and T / 8192 per step: the largest
    difference of x from the orbit's (relative), for each, and for their Richardson extrapolation (first order)."""
    orbit, runs = _implicit_runs(scene, shooting, s, omega, force, (4096, 8192), periods)
    size = np.max(np.abs(orbit))
    coarse, fine = (np.max(np.abs(x - orbit)) / size for x in runs)
    extrapolated = np.max(np.abs(2 * runs[1] - runs[0] - orbit)) / size
    return coarse, fine, extrapolated


def random_network(seed, dashpot=True):
    """Two or three nodes with masses, springs to the ground, a dashpot (unless not), a slider between nodes or
    to the ground, and a branch: TOML text and a force under which the sliders slip."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 4))
    nodes = [f"n{i}" for i in range(n)]
    elements = [("spring", [nodes[i], "ground"], {"k": rng.uniform(50, 400)}) for i in range(n)]
    c = rng.uniform(0.2, 2.0)
    if dashpot:
        elements.append(("dashpot", [nodes[-1], "ground"], {"c": c}))
    elements.append(("slider", [nodes[0], nodes[1]], {"alpha": rng.uniform(0.5, 2.0)}))
    elements.append(("slider", [nodes[-1], "ground"], {"alpha": rng.uniform(0.2, 1.0)}))
    elements.append(("branch", [nodes[0], nodes[-1]], {"k": rng.uniform(20, 100), "eta": rng.uniform(0.005, 0.02)}))
    return network_text(nodes, rng.uniform(0.5, 2.0, n), elements, load_node=nodes[0]), rng.uniform(3.0, 6.0)


# three sliders in a tree, all stuck at rest: releasing the most loaded one at a time ends in no consistent
# state (a review's case); the tensions' box problem finds the one there is (a-c slides, b-c holds)
TREE = network_text(["a", "b", "c"], [0.56, 2.9, 1.5], [
    ("spring", ["a", "ground"], {"k": 50.0}), ("spring", ["b", "ground"], {"k": 50.0}),
    ("spring", ["c", "ground"], {"k": 50.0}), ("slider", ["a", "c"], {"alpha": 1.75}),
    ("slider", ["b", "c"], {"alpha": 0.79}), ("slider", ["c", "ground"], {"alpha": 0.84})], load_node="a")


def _case(tmp_path, case, two_masses_force):
    """``(scene, force, f)`` of a named case: the two masses (at ``two_masses_force``), a chain of four, the
    slider tree, or a random network (``random N``; ``undamped N`` without its dashpot)."""
    from prandtl_fmu.scene import load_scene

    if case == "two masses":
        return load_scene(TWO_MASSES), two_masses_force, 1.9
    if case == "chain":
        return network(tmp_path, chain()), 6.0, 2.0
    if case == "slider tree":
        return network(tmp_path, TREE), 6.0, 0.5
    text, force = random_network(int(case[-1]), dashpot=case.startswith("random"))
    return network(tmp_path, text), force, 1.0


@pytest.mark.slow
@pytest.mark.parametrize("case", ["two masses", "chain", "slider tree", "random 1", "random 2", "random 3"])
def test_the_implicit_stepper_converges_to_the_orbit(tmp_path, case):
    """From the periodic state, one period of the implicit stepper (independent code: backward Euler with its
    own stick and slip) differs from the orbit by its first-order error: halved when the step is halved, and
    the Richardson extrapolation of the two is 10 times closer: the orbit is the time integration's limit."""
    scene, force, f = _case(tmp_path, case, 2.0)
    shooting, s, omega = periodic_state(scene, force, f)
    assert np.max(np.abs(s[:scene.network.n])) > 0
    coarse, fine, extrapolated = _implicit_errors(scene, shooting, s, omega, force)
    assert 1.7 < coarse / fine < 2.3, (coarse, fine)
    assert extrapolated < fine / 10, (fine, extrapolated)


@pytest.mark.slow
def test_a_stable_point_attracts_as_its_multipliers_say():
    """A slipping point of the two masses: the multipliers inside the unit circle; the motion from a perturbed
    state is the monodromy's prediction over six and twenty periods (the linearisation the multipliers come
    from), and after twenty periods it is as near the orbit as the largest multiplier says (within a factor 5:
    a complex pair of nearly the same size beats against it; a multiplier 0.1 off is a factor 40)."""
    from prandtl_fmu.frequency.floquet import is_stable
    from prandtl_fmu.scene import load_scene

    shooting, s, omega = periodic_state(load_scene(TWO_MASSES), 2.0, 1.9, steps=64)
    values = shooting.multipliers(s, omega)
    assert is_stable(values)
    largest = float(np.max(np.abs(values)))
    assert 0.05 < largest < 0.95
    turn = shooting.jacobian(s, omega) + np.eye(shooting.dimension)  # over half a period, turned
    delta = np.zeros(shooting.dimension)
    delta[0] = 1e-3 * np.max(np.abs(s))
    state, distances = s + delta, []
    for period in range(20):
        state = shooting.run(state, omega, 2)[0]  # one whole period
        distances.append(np.max(np.abs(state - s)))
        if period == 5:
            predicted = np.linalg.matrix_power(turn @ turn, 6) @ delta
            assert np.max(np.abs(state - s - predicted)) < 1e-3 * np.max(np.abs(predicted))
    # after 20 periods the prediction still holds, and the orbit is near at the largest multiplier's rate
    predicted = np.linalg.matrix_power(turn @ turn, 20) @ delta
    assert np.max(np.abs(state - s - predicted)) < 1e-2 * np.max(np.abs(predicted))
    assert 0.2 * largest**20 < distances[19] / delta[0] < 5 * largest**20


def energy_of(shooting, d):
    """The energy of a difference d of two states in the shooting's unknowns (x, v / omega_ref, u): kinetic,
    of the linear springs and of the branches' springs, written out here from the scene's elements."""
    n = shooting.system.n
    x, v, u = d[:n], d[n:2 * n] * shooting.reference, d[2 * n:]
    return 0.5 * (x @ shooting.stiffness_matrix @ x + v @ (shooting.system.mass * v) + u @ (shooting.bk * u))


@pytest.mark.slow
@pytest.mark.parametrize("case", ["two masses", "chain", "slider tree", "random 1", "random 2", "random 3",
                                  "random 4", "undamped 1", "undamped 2", "undamped 3"])
def test_the_motion_contracts_the_energy_of_the_difference_of_two_motions(tmp_path, case):
    """Why no point of these networks is unstable. Springs, dashpots (c >= 0), Coulomb sliders and Prandtl
    branches are monotone: for two motions under the same force, the energy of their difference (kinetic, of the
    springs, of the branches' springs) never grows, as in the uniqueness proof of Proposition 2.1 of the M2AN
    paper (its derivative is minus the dashpots' dissipation and minus the sliders' forces' differences times
    the velocities' differences, each <= 0). So every Floquet multiplier is at most 1 in modulus. Checked on
    the orbit's code, event by event, from pairs of states near and far (sticking, slipping, the branches anywhere
    in their range), over a 200th of a period to three half periods, with and without dashpots: the energy of the
    difference never grows beyond rounding (an energy with its springs' or masses' term off by a factor 2 grows
    here), and it
    falls."""
    from prandtl_fmu.frequency.shooting import NetworkShooting

    scene, force, f = _case(tmp_path, case, 3.0)
    n, rng = scene.network.n, np.random.default_rng(len(case))
    fell = []
    for faster in (1, 10, 100):  # the run over half a period of a faster force: a shorter time
        omega = 2 * math.pi * f * faster
        shooting = NetworkShooting(scene, force, None, 64, 7, omega)
        size = force / shooting.stiffness
        for trial in range(8):
            first = np.concatenate((rng.normal(0, size, n), rng.normal(0, size, n),
                                    rng.uniform(-1, 1) * shooting.eta))
            scale = 10.0 ** -rng.integers(0, 7)  # from a state far away to one a hair away
            second = first + scale * np.concatenate((rng.normal(0, size, n), rng.normal(0, size, n),
                                                     rng.uniform(-1, 1, shooting.eta.size) * shooting.eta))
            second[2 * n:] = np.clip(second[2 * n:], -shooting.eta, shooting.eta)
            before = energy_of(shooting, first - second)
            # the norm of the difference may grow by the rounding of the states (1e-13 of their norm)
            rounding = 1e-13 * math.sqrt(energy_of(shooting, np.abs(first) + np.abs(second)))
            for half_periods in (1, 3):
                after = energy_of(shooting, shooting.run(first, omega, half_periods)[0] -
                                  shooting.run(second, omega, half_periods)[0])
                assert math.sqrt(after) <= math.sqrt(before) + rounding, (faster, trial, half_periods, after / before)
                fell.append(after / before)
    assert min(fell) < 0.99 and max(fell) > 0.9, (min(fell), max(fell))  # it falls; short runs come near 1


@pytest.mark.slow
def test_the_curve_steps_over_the_kinks_where_nodes_start_or_stop_slipping(tmp_path, monkeypatch):
    """A chain of three at F0 = 2.5 N from 1 to 4 Hz: its nodes start and stop slipping along the curve, each a
    kink where Newton on the arc-length hyperplane cycles between the Jacobians of the two sides (the curve
    stopped at 1.52 Hz). Now the steps over the kinks are taken (counted here), the curve reaches 4 Hz going
    ahead in frequency (its orientation kept by the sign of det [dR/dy; t], not by the tangent before the
    kink, which flipped it back and forth), and the points on either side of every kink are the periodic state
    that Newton finds at their frequency alone, from rest, and the limit of the implicit stepper's motion."""
    from prandtl_fmu.frequency import continuation
    from prandtl_fmu.frequency.shooting import NetworkShooting

    taken = []
    damped = continuation._damped

    def counted(*args):
        point = damped(*args)
        if point is not None:
            taken.append(point[1])
        return point

    monkeypatch.setattr(continuation, "_damped", counted)
    scene = network(tmp_path, chain(3))
    low, high = 2 * math.pi * 1.0, 2 * math.pi * 4.0
    shooting = NetworkShooting(scene, 2.5, None, 64, 7, math.sqrt(low * high))
    points = continuation.continue_curve(shooting, low, high, 2)
    omega = np.array([w for w, _, _ in points])
    assert omega[-1] == high and np.all(np.diff(omega) > 0)
    assert len(taken) >= 3, f"the curve took {len(taken)} steps over a kink: this chain no longer tests them"
    at = {w: s for w, s, _ in points}
    for w in taken[:4]:
        index = int(np.flatnonzero(omega == w)[0])
        for near in (omega[index - 1], omega[index]):
            alone = shooting.solve_at(near)
            assert np.max(np.abs(alone - at[near])) <= 1e-8 * np.max(np.abs(alone)), near / (2 * math.pi)
    # independent code: the implicit stepper (backward Euler, its own stick and slip) from the points on either
    # side of the first kinks, at 8192 to 65536 steps a period, tends to their orbit: its error halves with the
    # step, with no floor (an orbit off by d would leave 2 e(2M) - e(M) = d; measured 1e-5 of 6e-4)
    for w in taken[:2]:
        index = int(np.flatnonzero(omega == w)[0])
        for near in (omega[index - 1], omega[index]):
            orbit, runs = _implicit_runs(scene, shooting, at[near], near, 2.5, (8192, 16384, 32768, 65536))
            errors = [np.max(np.abs(x - orbit)) / np.max(np.abs(orbit)) for x in runs]
            ratios = [a / b for a, b in zip(errors, errors[1:])]
            assert all(1.8 < r < 2.2 for r in ratios), (near / (2 * math.pi), errors)
            assert abs(2 * errors[-1] - errors[-2]) < 0.05 * errors[-1], (near / (2 * math.pi), errors)


@pytest.mark.slow
def test_with_many_unknowns_the_corrector_keeps_its_jacobian_and_the_points_are_the_same(tmp_path, monkeypatch):
    """A chain of six (12 unknowns): the continuation's corrector keeps the last point's Jacobian (the chord
    method: a run of the motion an iteration, not 13), counted here; the points it gives are the periodic state
    that Newton finds at their frequency alone, from rest, to 1e-8."""
    from prandtl_fmu.frequency import continuation
    from prandtl_fmu.frequency.shooting import NetworkShooting

    kept = []
    chord = continuation._chord

    def counted(*args):
        point = chord(*args)
        kept.append(point is not None)
        return point

    monkeypatch.setattr(continuation, "_chord", counted)
    scene = network(tmp_path, chain(6))
    low, high = 2 * math.pi * 1.0, 2 * math.pi * 2.5
    shooting = NetworkShooting(scene, 6.0, None, 64, 7, math.sqrt(low * high))
    assert shooting.costly_jacobian
    points = continuation.continue_curve(shooting, low, high, 2)
    assert points[-1][0] == high and sum(kept) >= len(points) // 2, (sum(kept), len(kept), len(points))
    for w, s, _ in points[1:-1:max(1, len(points) // 5)]:
        alone = shooting.solve_at(w)
        assert np.max(np.abs(alone - s)) <= 1e-8 * np.max(np.abs(alone)), w / (2 * math.pi)


@pytest.mark.slow
def test_the_chain_on_a_support_from_the_command_line(tmp_path):
    """describe on a chain of four nodes on a support: the contract's columns, every node's amplitude, a
    stable column of true or false, the figure."""
    pytest.importorskip("matplotlib")
    path = tmp_path / "chain.toml"
    path.write_text(chain())
    out, plot = tmp_path / "curve.csv", tmp_path / "curve.png"
    assert main(["describe", str(path), "--force-amplitude", "6", "--frequencies", "1,4", "--out", str(out),
                 "--plot", str(plot)]) == 0
    table = read_csv(out)
    assert list(table)[:8] == ["frequency", "amplitude", "phase", "stable", "amplitude_n1", "amplitude_n2",
                               "amplitude_n3", "amplitude_n4"]
    f = np.array(table["frequency"], dtype=float)
    assert f[0] == 1.0 and f[-1] == pytest.approx(4.0, rel=1e-12) and np.all(np.diff(f) != 0)
    assert set(table["stable"]) <= {"true", "false"}
    n1, n4 = (np.array(table[f"amplitude_{node}"], dtype=float) for node in ("n1", "n4"))
    assert np.allclose(n1, np.array(table["amplitude"], dtype=float), rtol=1e-14, atol=0)  # the first node
    assert np.all(n1 < n4)  # the load on n4: the slip front runs in from it, the far end moves least
    assert "nan" not in out.read_text().lower()
    assert plot.read_bytes()[:4] == b"\x89PNG"


# a slider to the ground and a dashpot to b on a massless node: its position would follow a first-order motion
# with a threshold (the slider and the dashpot side by side to one end, or a branch's series dashpot, are taken:
# test_series.py)
DASHPOT_ON_A_MASSLESS_NODE = network_text(["a", "j", "b"], [1.0, 0.0, 1.0], [
    ("spring", ["a", "ground"], {"k": 1.0}), ("spring", ["a", "j"], {"k": 1.0}),
    ("spring", ["b", "ground"], {"k": 1.0}), ("slider", ["j", "ground"], {"alpha": 0.1}),
    ("dashpot", ["j", "b"], {"c": 0.5}), ("slider", ["a", "ground"], {"alpha": 0.1})], load_node="a")


# (a massless node on a slider: a lever, or refused where it cannot be one: test_series.py; a cubic spring and
# branches with series dashpots: taken, test_cubic_shooting.py)
@pytest.mark.parametrize("text, culprit", [(DASHPOT_ON_A_MASSLESS_NODE, "node j is massless, with dashpot dashpot_1")],
                         ids=["a dashpot and a slider to two ends on a massless node"])
def test_what_the_network_s_shooting_refuses_is_one_line(tmp_path, capsys, text, culprit):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    out = tmp_path / "out.csv"
    assert main(["describe", str(path), "--force-amplitude", "1", "--frequencies", "0.1,0.2",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert culprit in err and "prandtl-fmu run" in err and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err and not out.exists()
