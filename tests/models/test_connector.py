"""The element as a connector (displacement in, force out): library, FMU, OSP description.

Against independent straightforward code: the play operator u_i <- clip(u_i + dx, -eta_i, eta_i) written
out in numpy.
"""
import subprocess
import sys

import numpy as np
import pytest

from prandtl_fmu import parse_scene
from prandtl_fmu.connector import Connector, displacement_response

from tests.conftest import ROOT, scene_text
from tests.fmu_tools import Slave

SOLVER = {"step": 0.01, "stop_time": 10.0, "output_interval": 0.01}


def connector_tables(k, eta, u0=None, k0=0.7, k3=0.3, c=0.05, name="bushing"):
    branches = {"k": list(k), "eta": list(eta)}
    if u0 is not None:
        branches["u0"] = list(u0)
    tables = {"name": name, "spring": {"k0": k0} if k0 is not None else None,
              "cubic": {"k3": k3} if k3 is not None else None, "damper": {"c": c} if c is not None else None,
              "branches": branches, "fmu": {"causality": "displacement"}, "solver": SOLVER}
    return {key: value for key, value in tables.items() if value is not None}


def connector_scene(*args, **kwargs):
    return parse_scene(scene_text(connector_tables(*args, **kwargs)), "connector.toml")


def reference_forces(k, eta, u0, k0, k3, c, x, v):
    """The force along the samples, written out: one clip per branch and sample."""
    k, eta = np.asarray(k, float), np.asarray(eta, float)
    u = np.zeros_like(k) if u0 is None else np.array(u0, float)
    previous, forces = 0.0, []
    for xj, vj in zip(x, v):
        u = np.clip(u + (xj - previous), -eta, eta)
        previous = xj
        forces.append((k0 or 0.0) * xj + (k3 or 0.0) * xj ** 3 + (c or 0.0) * vj + k @ u)
    return np.array(forces)


def random_history(rng, count=600, scale=1.0):
    """A displacement history with reversals of every size, and its velocity."""
    t = np.linspace(0.0, 20.0, count)
    x = scale * (np.sin(0.9 * t) * np.exp(-0.05 * t) + 0.3 * np.sin(3.1 * t + rng.uniform(0, 6))
                 + 0.05 * rng.standard_normal(count).cumsum() / np.sqrt(count))
    return t, x, np.gradient(x, t)


@pytest.mark.parametrize("n", [1, 5, 80])  # 80 branches: the memory stack
def test_the_force_along_a_history_is_the_play_operator_written_out(n):
    rng = np.random.default_rng(n)
    for trial in range(8):
        k = rng.uniform(0.1, 3.0, n)
        eta = rng.uniform(0.01, 1.0, n)
        u0 = rng.uniform(-1, 1, n) * eta * (0.0 if n >= 64 else 1.0)  # the stack needs an admissible start
        k0, k3, c = (None if rng.random() < 0.3 else rng.uniform(0, 2) for _ in range(3))
        scene = connector_scene(k, eta, u0, k0, k3, c)
        t, x, v = random_history(rng, scale=rng.uniform(0.1, 2.0))
        forces = displacement_response(scene, x, v)
        expected = reference_forces(k, eta, u0, k0, k3, c, x, v)
        scale = np.abs(expected).max()
        np.testing.assert_allclose(forces, expected, rtol=0, atol=1e-12 * scale)


def test_the_stateful_connector_equals_the_whole_history_and_preview_changes_nothing():
    rng = np.random.default_rng(7)
    scene = connector_scene([1.0, 2.0, 0.5], [0.1, 0.25, 0.6], [0.05, -0.1, 0.0])
    t, x, v = random_history(rng)
    expected = displacement_response(scene, x, v)
    connector = Connector(scene)
    for j in range(len(x)):
        state = connector.get_state()
        for trial in rng.uniform(-2, 2, 3):  # a master iterating on the input: no trace left
            connector.preview(trial, 0.3)
        assert connector.get_state() == state
        previewed = connector.preview(x[j], v[j])
        connector.move_to(x[j], v[j], t[j])
        assert previewed == connector.force == expected[j]


def test_the_force_does_not_depend_on_how_a_linear_path_is_sampled():
    """Rate independence: refining a piecewise-linear path (points on its segments) changes nothing."""
    rng = np.random.default_rng(3)
    scene = connector_scene(rng.uniform(0.1, 2, 6), rng.uniform(0.05, 0.8, 6), c=None)
    coarse = np.concatenate([[0.0], rng.uniform(-1.5, 1.5, 60)])
    fine, keep = [], []
    for a, b in zip(coarse[:-1], coarse[1:]):
        for s in np.sort(rng.uniform(0, 1, rng.integers(0, 5))):
            fine.append(a + s * (b - a))
        fine.append(b)
        keep.append(len(fine) - 1)
    forces_coarse = displacement_response(scene, coarse[1:])
    forces_fine = displacement_response(scene, np.array(fine))
    np.testing.assert_allclose(forces_fine[keep], forces_coarse, rtol=0, atol=1e-13)


def test_stiffness_is_the_slope_of_the_force_on_a_sticking_state_and_of_each_side_on_a_slipping_one():
    scene = connector_scene([1.0, 2.0, 0.5], [0.1, 0.25, 0.6], k0=0.7, k3=0.3, c=None)
    connector = Connector(scene)
    for x in (0.0, 0.4, 0.32):  # loading to 0.4 (two branches slide), then back to 0.32: all stick
        connector.move_to(x, 0.0)
    delta = 1e-7
    for direction in (1.0, -1.0):
        slope = (connector.preview(0.32 + direction * delta, 0.0) - connector.force) / (direction * delta)
        assert connector.stiffness(direction) == pytest.approx(slope, rel=1e-6)
    assert connector.stiffness(1.0) == pytest.approx(0.7 + 0.9 * 0.32 ** 2 + 3.5, rel=1e-12)
    connector.move_to(0.5, 0.0)  # now the two small branches sit on +eta: they slide further up, stick down
    up = (connector.preview(0.5 + delta, 0.0) - connector.force) / delta
    down = (connector.force - connector.preview(0.5 - delta, 0.0)) / delta
    assert connector.stiffness(1.0) == pytest.approx(up, rel=1e-6)
    assert connector.stiffness(-1.0) == pytest.approx(down, rel=1e-6)
    assert connector.stiffness(0.0) == connector.stiffness(1.0)  # v = 0: the direction of the last motion
    assert up < down


def test_the_energy_account_closes_along_the_path():
    """Stored energy change + sliders' dissipation = the work of the elastic force along the path."""
    rng = np.random.default_rng(11)
    k, eta = rng.uniform(0.2, 2, 5), rng.uniform(0.05, 0.5, 5)
    scene = connector_scene(k, eta, k0=0.4, k3=0.2, c=None)
    t, x, v = random_history(rng, count=200)
    samples = np.concatenate([[0.0], x])
    fine = np.concatenate([np.linspace(a, b, 400, endpoint=False) for a, b in zip(samples[:-1], samples[1:])]
                          + [[samples[-1]]])
    forces = displacement_response(scene, fine)
    work = np.sum(0.5 * (forces[1:] + forces[:-1]) * np.diff(fine)) + 0.5 * forces[0] * fine[0]
    connector = Connector(scene)
    for xj in x:
        connector.move_to(xj, 0.0)
    energy = connector.energy()
    assert energy["dissipated_sliders"] > 0.1 * abs(work)
    assert energy["stored_energy"] + energy["dissipated_sliders"] == pytest.approx(work, rel=1e-5)


def test_the_continuous_connector_is_the_limit_of_sampled_branches():
    tables = {"name": "continuum", "spring": {"k0": 0.5},
              "branches": {"continuum": True, "k_total": 2.0, "eta_range": [0.05, 0.6]},
              "fmu": {"causality": "displacement"}, "solver": SOLVER}
    rng = np.random.default_rng(5)
    t, x, v = random_history(rng)
    exact = displacement_response(parse_scene(scene_text(tables)), x)
    errors = []
    for n in (16, 64, 256):
        tables["branches"] = {"count": n, "k_total": 2.0, "eta_range": [0.05, 0.6], "sampling": "midpoint"}
        errors.append(np.abs(displacement_response(parse_scene(scene_text(tables)), x) - exact).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:])) / 2
    assert errors[-1] < errors[0] and np.all(orders > 1.5), (errors, orders)


def test_a_connector_scene_with_a_mass_is_refused_in_one_line(tmp_path):
    tables = connector_tables([1.0], [0.1])
    tables["mass"] = {"m": 1.0}
    path = tmp_path / "bad.toml"
    path.write_text(scene_text(tables))
    run = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "-o", str(tmp_path / "a.fmu")],
                         capture_output=True, text=True)
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1
    assert "[fmu] causality" in run.stderr and "remove [mass]" in run.stderr
    assert not list(tmp_path.glob("*.fmu"))


def test_build_causality_option_makes_the_connector_and_refuses_a_contradiction(tmp_path):
    tables = connector_tables([1.0], [0.1])
    del tables["fmu"]
    path = tmp_path / "plain.toml"
    path.write_text(scene_text(tables))
    run = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(path), "-o", str(tmp_path / "c.fmu"),
                          "--causality", "displacement", "--osp"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == [str(tmp_path / "c.fmu"), str(tmp_path / "bushing_OspModelDescription.xml")]
    from fmpy import read_model_description

    md = read_model_description(str(tmp_path / "c.fmu"))
    assert md.coSimulation.modelIdentifier == "PrandtlConnector"
    assert [v.name for v in md.modelVariables if v.causality == "input"] == ["x", "v"]
    contradicting = tmp_path / "contra.toml"
    contradicting.write_text(scene_text(connector_tables([1.0], [0.1])))
    run = subprocess.run([sys.executable, "-m", "prandtl_fmu", "build", str(contradicting), "-o",
                          str(tmp_path / "d.fmu"), "--causality", "force"], capture_output=True, text=True)
    assert run.returncode == 2 and "contradicts --causality" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and not (tmp_path / "d.fmu").exists()


# ------------------------------------------------------------------ the FMU


@pytest.fixture(scope="module")
def connector_fmu(tmp_path_factory):
    from prandtl_fmu.fmu.build import build_fmu

    folder = tmp_path_factory.mktemp("connector")
    path = folder / "connector.toml"
    path.write_text(scene_text(connector_tables([1.0, 2.0, 0.5, 3.0], [0.1, 0.25, 0.6, 0.05],
                                                [0.05, -0.1, 0.0, 0.0])))
    return build_fmu(path, folder / "connector.fmu"), path


def _input_signal(t, x, v):
    signal = np.zeros(len(t), dtype=[("time", float), ("x", float), ("v", float)])
    signal["time"], signal["x"], signal["v"] = t, x, v
    return signal


def test_fmpy_drives_the_connector_fmu_to_the_play_operator(connector_fmu):
    from fmpy import simulate_fmu

    from prandtl_fmu import load_scene

    fmu, scene_path = connector_fmu
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 10.0, 1001)
    _, x, v = random_history(rng, count=1001)
    for repeat in range(2):  # a second run in this process: a new extraction folder, the first one deleted
        result = simulate_fmu(str(fmu), stop_time=10.0, output_interval=0.01, input=_input_signal(t, x, v),
                              output=["force", "stiffness", "stored_energy", "dissipated_sliders"])
        expected, dissipated = displacement_response(load_scene(scene_path), x, v, energy=True)
        # FMPy records after doStep(t_k), before it sets the input of t_k+1: row k + 1 shows the sample k
        np.testing.assert_allclose(result["force"][1:], expected[:-1], rtol=0, atol=1e-12)
        assert result["force"][0] == expected[0]
        assert result["dissipated_sliders"][-1] <= dissipated


def test_the_fmu_stiffness_is_the_finite_difference_of_its_force_on_a_sticking_state(connector_fmu):
    fmu, _ = connector_fmu
    slave = Slave(fmu)
    try:
        for x in (0.2, 0.5, 0.45):  # load, then unload a little: every branch sticks
            slave.set("x", x)
            slave.step(0.1)
        slave.set("v", -0.1)
        force, stiffness = slave.get("force", "stiffness")
        delta = 1e-7
        slave.set("x", 0.45 - delta)  # set without stepping: the output previews the input
        slope = (force - slave.get("force")) / delta
        assert stiffness == pytest.approx(slope, rel=1e-6)
        slave.set("x", 0.45)
        assert slave.get("force") == force  # the preview left no trace
        slave.set("v", 0.1)
        slave.set("x", 0.9)  # far beyond every threshold: the stiffness going on up is k0 + 3 k3 x^2 only
        assert slave.get("stiffness") == pytest.approx(0.7 + 0.9 * 0.81, rel=1e-12)
    finally:
        slave.close()


def test_the_connector_fmu_state_round_trips_and_a_bad_input_is_discarded(connector_fmu):
    from fmpy.fmi1 import FMICallException

    fmu, _ = connector_fmu
    slave = Slave(fmu)
    try:
        for x in np.linspace(0, 0.7, 8):
            slave.set("x", x)
            slave.step(0.05)
        blob = slave.fmu.serializeFMUstate(slave.fmu.getFMUstate())
        tail = []
        for x in (0.3, -0.2, 0.1):
            slave.set("x", x)
            slave.step(0.05)
            tail.append(slave.get("force"))
        slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(blob))
        slave.time = 0.4
        again = []
        for x in (0.3, -0.2, 0.1):
            slave.set("x", x)
            slave.step(0.05)
            again.append(slave.get("force"))
        assert again == tail
        before = slave.get("force")
        slave.set("x", float("nan"))
        with pytest.raises(FMICallException) as refused:
            slave.fmu.doStep(slave.time, 0.05)
        assert refused.value.status == 2  # fmi2Discard
        assert any("x = nan" in message for _, message in slave.messages)
        slave.set("x", 0.1)
        assert slave.get("force") == before  # nothing moved
    finally:
        slave.close()


def test_a_master_refining_its_steps_gets_the_same_force_on_a_linear_input(connector_fmu):
    """FMPy interpolates the input linearly: halving the communication step on a piecewise-linear x changes
    nothing at the common points (rate independence), whatever the velocity does to the dashpot term."""
    from fmpy import simulate_fmu

    fmu, _ = connector_fmu
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    x = np.array([0.0, 0.8, -0.3, 0.2, 0.5])
    signal = _input_signal(t, x, np.zeros_like(x))
    coarse = simulate_fmu(str(fmu), stop_time=4.0, output_interval=0.1, input=signal, output=["force"])
    fine = simulate_fmu(str(fmu), stop_time=4.0, output_interval=0.025, input=signal, output=["force"])
    # the row at t shows the sample taken one step earlier: compare at the segment ends, sampled by both
    for end in (1.0, 2.0, 3.0):
        row_coarse = np.argmin(np.abs(coarse["time"] - (end + 0.1)))
        row_fine = np.argmin(np.abs(fine["time"] - (end + 0.025)))
        assert coarse["force"][row_coarse] == pytest.approx(fine["force"][row_fine], abs=1e-13)


# ------------------------------------------------------------------ OSP


def _validate_osp(xml_bytes):
    from lxml import etree

    schema = etree.XMLSchema(etree.parse(str(ROOT / "tests" / "data" / "osp" / "OspModelDescription-1.0.1.xsd")))
    document = etree.fromstring(xml_bytes)
    schema.assertValid(document)
    return document


@pytest.mark.parametrize("causality", ["force", "displacement"])
def test_each_fmu_ships_an_osp_description_valid_against_the_schema_with_opposite_causalities(tmp_path, causality):
    import zipfile

    from fmpy import read_model_description

    from prandtl_fmu.fmu.build import build_fmu

    tables = connector_tables([1.0, 2.0], [0.1, 0.3], name="port")
    tables["fmu"] = {"causality": causality}
    if causality == "force":
        tables["mass"] = {"m": 1.0}
    path = tmp_path / "port.toml"
    path.write_text(scene_text(tables))
    fmu = build_fmu(path, tmp_path / "port.fmu", osp=True)
    md = read_model_description(str(fmu))
    identifier = md.coSimulation.modelIdentifier
    with zipfile.ZipFile(fmu) as archive:
        inside = archive.read(f"resources/{identifier}_OspModelDescription.xml")
    beside = (tmp_path / f"{md.modelName}_OspModelDescription.xml").read_bytes()
    assert inside == beside
    document = _validate_osp(inside)
    causalities = {v.name: v.causality for v in md.modelVariables}
    units = {v.name: v.declaredType.unit if v.declaredType else v.unit for v in md.modelVariables}
    namespace = {"osp": "https://open-simulation-platform.com/OspModelDescription/1.0.1"}
    for port, motion in (("LinearMechanicalPort", "LinearVelocity"), ("LinearMechanicalQuasiPort",
                                                                       "LinearDisplacement")):
        (group,) = document.findall(f"osp:VariableGroups/osp:{port}", namespace)
        (force,) = group.findall("osp:Force/osp:Variable", namespace)
        (moving,) = group.findall(f"osp:{motion}/osp:Variable", namespace)
        pair = {causalities[force.get("ref")], causalities[moving.get("ref")]}
        assert pair == {"input", "output"}
        assert units[force.get("ref")] == force.get("unit") == "N"
        assert units[moving.get("ref")] == moving.get("unit")


def test_a_host_python_without_numba_gets_a_logged_reason_naming_it_and_the_recipe(tmp_path, connector_fmu):
    """What a non-Python host without PYTHONPATH meets: the FMU's import fails with one logged reason."""
    script = tmp_path / "host.py"
    script.write_text(
        "import os, sys\n"
        "sys.modules['numba'] = None  # a host Python without numba\n"
        "from fmpy import simulate_fmu\n"
        "messages = []\n"
        "try:\n"
        "    simulate_fmu(sys.argv[1], stop_time=0.1, debug_logging=True,\n"
        "                 logger=lambda c, i, s, cat, m: messages.append(m.decode()))\n"
        "except Exception as exc:\n"
        "    messages.append('raised ' + type(exc).__name__)\n"
        "print('\\n'.join(messages))\n")
    run = subprocess.run([sys.executable, str(script), str(connector_fmu[0])], capture_output=True, text=True,
                         timeout=300)
    assert "raised" in run.stdout
    assert "numba" in run.stdout and "in the host's Python" in run.stdout and "PYTHONPATH" in run.stdout


# ------------------------------------------------------------------ the inputs' derivatives over a step (issue 61)

@pytest.mark.parametrize("n", [5, 80])  # 80 branches: the memory stack
def test_advance_follows_the_polynomial_path_through_its_turning_point(n):
    """Connector.advance(x, v, time, H, x_derivatives=(x', x''), v_derivatives=(v', v'')): the sample committed
    at ``time``, then the play operator along x + x' t + x'' t^2/2 over H, written out here as one clip per
    monotone piece (the turning point t* = -x'/x'' found in the test); the dashpot's dissipation the integral of
    c v^2 by numpy's polynomials; the end time, x, v, force and sliders' dissipation as written out. Paths that
    turn inside the step reach branches the straight move from start to end would not."""
    rng = np.random.default_rng(n)
    k, eta = rng.uniform(0.1, 3.0, n), rng.uniform(0.01, 0.3, n)
    k0, k3, c = 0.7, 0.3, 0.05
    connector = Connector(connector_scene(k, eta, k0=k0, k3=k3, c=c))
    u, x_now, time, damper, turned = np.zeros(n), 0.0, 0.0, 0.0, 0
    for j in range(40):
        x, v = float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-1, 1))
        xd, vd = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2)
        H = float(rng.choice([0.05, 0.3, 1.0]))
        if j % 3 == 0:  # a turn at 0.4 H
            xd[1] = -xd[0] / (0.4 * H)
        connector.advance(x, v, time, H, x_derivatives=xd.tolist(), v_derivatives=vd.tolist())
        u = np.clip(u + (x - x_now), -eta, eta)  # the sample committed at time
        path = np.polynomial.Polynomial([x, xd[0], xd[1] / 2])
        turn = -xd[0] / xd[1]
        points = [0.0] + ([turn] if 0 < turn < H else []) + [H]
        turned += len(points) == 3
        for a, b in zip(points[:-1], points[1:]):
            u = np.clip(u + (path(b) - path(a)), -eta, eta)
        speed = np.polynomial.Polynomial([v, vd[0], vd[1] / 2])
        damper += c * (speed ** 2).integ()(H)
        x_now, v_end, time = path(H), speed(H), time + H
        force = k0 * x_now + k3 * x_now ** 3 + c * v_end + k @ u
        assert connector.time == time
        assert connector.x == pytest.approx(x_now, abs=1e-14) and connector.v == pytest.approx(v_end, abs=1e-14)
        assert connector.force == pytest.approx(force, rel=1e-11, abs=1e-12), j
        assert connector.energy()["dissipated_damper"] == pytest.approx(damper, rel=1e-11)
        x_now = connector.x  # (the next sample is committed with no time between: no dashpot work)
    assert turned >= 14


def test_advance_without_derivatives_is_the_held_sample_and_refuses_what_it_cannot_follow():
    """Without derivatives advance is move_to at the communication point (the connector stays there); a
    non-finite derivative, a negative duration, derivatives on branches with series dashpots and a path that
    overflows are refused, the connector unchanged."""
    scene = connector_scene([1.0, 2.0], [0.1, 0.2])
    held, moved = Connector(scene), Connector(scene)
    held.advance(0.3, 0.1, 0.5, 0.2)
    moved.move_to(0.3, 0.1, 0.5)
    assert held.get_state() == moved.get_state() and held.time == 0.5
    for kwargs, words in (({"x_derivatives": (1.0, float("nan"))}, "x_derivatives must be two finite"),
                          ({"v_derivatives": (1.0,)}, "v_derivatives must be two finite")):
        with pytest.raises(ValueError, match=words):
            held.advance(0.2, 0.0, 0.6, 0.1, **kwargs)
    with pytest.raises(ValueError, match="duration must be finite"):
        held.advance(0.2, 0.0, 0.6, -0.1, x_derivatives=(1.0, 0.0))
    series = Connector(parse_scene(scene_text({**connector_tables([1.0], [0.1]),
                                              "branches": {"k": [1.0], "eta": [0.1], "c": [0.5]}}), "s.toml"))
    with pytest.raises(ValueError, match="series dashpots or effects with memory"):
        series.advance(0.2, 0.0, 0.0, 0.1, x_derivatives=(1.0, 0.0))
    from prandtl_fmu.stepping import ElementError
    for xd in ((1e308, 0.0), (1e308, -1e308)):  # the path's end, or its turning point, beyond the floats
        with pytest.raises(ElementError, match="x would not be finite"):
            held.advance(0.2, 0.0, 0.6, 10.0, x_derivatives=xd)
    assert held.get_state() == moved.get_state() and series.time == 0.0


# ------------------------------------------------------------------ the force's time derivatives (issue 61)

def _force_along(k, eta, u, k0, k3, c, x, path, speed, t):
    """The force at time t along the path x + path(t) - path(0) from elongations u, written out (one clip per branch:
    the path is monotone over [0, t] for the small t used here)."""
    moved = np.clip(u + (path(t) - path(0.0)), -eta, eta)
    return k0 * path(t) + k3 * path(t) ** 3 + c * speed(t) + k @ moved


@pytest.mark.parametrize("n", [5, 80])  # 80 branches: the memory stack
def test_the_force_s_derivatives_are_the_slopes_of_the_force_along_the_inputs_path(n):
    """Connector.output_derivatives(x, v, x', v'): F' and F'' at the preview of (x, v) along the path x + x' t +
    x'' t^2/2 (x' = v, x'' = v' where x's derivatives are not given; v' = v'' = 0 where v's are not), against
    one-sided differences (second order) of the force written out here along that path (the play operator as one
    clip per branch), to 1e-6 relative (1e-5 for F''): random states, with derivatives, without, a path that
    starts at rest (x' = 0: its direction is x''s), and a branch on its threshold (sliding on when pushed,
    sticking when pulled off)."""
    rng = np.random.default_rng(n + 61)
    k, eta = rng.uniform(0.1, 3.0, n), rng.uniform(0.01, 0.3, n)
    k0, k3, c = 0.7, 0.3, 0.05
    connector = Connector(connector_scene(k, eta, k0=k0, k3=k3, c=c))
    t, history, speeds = random_history(rng, count=80, scale=0.4)
    checked = 0
    for j, (time, xj, vj) in enumerate(zip(t, history, speeds)):
        connector.move_to(float(xj), float(vj), float(time))
        if j % 4:
            continue
        u = connector.elongations()
        x = float(xj) if j % 8 else float(xj) + 1e-3  # the preview of a new x (from the committed one)
        v = float(rng.uniform(-1, 1))
        moved = np.clip(u + (x - connector.x), -eta, eta)
        cases = [(None, None, (v, v and 0.0), (0.0, 0.0)),
                 (rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), None, None),
                 ((0.0, float(rng.choice([-1.5, 1.5]))), (0.3, -0.7), None, None)]
        for xd, vd, x_path, v_path in cases:
            x1, x2 = x_path if x_path is not None else xd
            v1, v2 = v_path if v_path is not None else vd
            if x_path is not None:
                x2 = v1  # x'' = v' = 0: held
            path = np.polynomial.Polynomial([x, x1, x2 / 2])
            speed = np.polynomial.Polynomial([v, v1, v2 / 2])
            # one-sided differences of second order, over an interval where no branch reaches its threshold (at
            # 1e-5 the second is rounding: |F| / delta^2)
            ahead = np.sign(x1 if x1 else x2)
            room = eta - ahead * moved
            room = room[room > 0]
            delta = min(3e-4, room.min() / (8 * (abs(x1) + abs(x2)))) if room.size else 3e-4
            if delta < 1e-5:
                continue
            f0, f1, f2, f3 = (_force_along(k, eta, moved, k0, k3, c, x, path, speed, s * delta) for s in range(4))
            first = (-3 * f0 + 4 * f1 - f2) / (2 * delta)
            second = (2 * f0 - 5 * f1 + 4 * f2 - f3) / delta ** 2
            got = connector.output_derivatives(x, v, None if xd is None else tuple(xd),
                                               None if vd is None else tuple(vd))
            assert got[("force", 1)] == pytest.approx(first, rel=1e-6, abs=1e-7), (j, xd, vd)
            assert got[("force", 2)] == pytest.approx(second, rel=1e-5, abs=1e-6), (j, xd, vd)
            checked += 1
    assert checked >= 30
    # a branch on its threshold: a move up leaves the branches it reached on +eta; moving on up they slide, turning
    # back they stick (F'' at x' = 0 takes the direction of x'')
    connector = Connector(connector_scene([1.0, 2.0], [0.1, 0.5], k0=0.5, k3=None, c=None))
    connector.move_to(0.3, 0.0, 1.0)
    up = connector.output_derivatives(0.3, 1.0)[("force", 1)]
    down = connector.output_derivatives(0.3, -1.0)[("force", 1)]
    assert (up, down) == (0.5 + 2.0, -(0.5 + 1.0 + 2.0))
    assert connector.output_derivatives(0.3, 0.0, (0.0, -2.0))[("force", 2)] == -2.0 * 3.5
    assert connector.output_derivatives(0.3, 0.0, (0.0, 2.0))[("force", 2)] == 2.0 * 2.5


def test_the_force_s_derivatives_refuse_what_they_cannot_give():
    """Series dashpots and effects with memory (their forces' rates are not the tangent's), a non-finite input:
    ValueError naming it, the connector unchanged."""
    series = Connector(parse_scene(scene_text({**connector_tables([1.0], [0.1]),
                                              "branches": {"k": [1.0], "eta": [0.1], "c": [0.5]}}), "s.toml"))
    with pytest.raises(ValueError, match="series dashpots or effects with memory"):
        series.output_derivatives(0.1, 0.0)
    delayed = Connector(parse_scene(scene_text({**connector_tables([1.0], [0.1]),
                                               "delay": {"gain": 0.5, "tau": 0.3}}), "d.toml"))
    with pytest.raises(ValueError, match="series dashpots or effects with memory"):
        delayed.output_derivatives(0.1, 0.0)
    plain = Connector(connector_scene([1.0], [0.1]))
    before = plain.get_state()
    with pytest.raises(ValueError, match="must be finite"):
        plain.output_derivatives(float("nan"), 0.0)
    with pytest.raises(ValueError, match="x_derivatives must be two finite"):
        plain.output_derivatives(0.1, 0.0, (1.0, float("inf")))
    assert plain.get_state() == before
