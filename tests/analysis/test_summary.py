"""Many runs in one compiled call (summary.summarize_many, kernels/batch.py): random scenes of every structure,
packed together, each equal bit for bit to simulate's own time loop run alone; one compiled call per structure;
failures and warnings stay with their run; the result does not depend on how the runs are cut into calls."""
import math

import numpy as np
import pytest

from prandtl_fmu import parse_scene
from prandtl_fmu import summary as summary_module
from prandtl_fmu.driver import simulate
from prandtl_fmu.stepping import ElementError
from prandtl_fmu.scene import SceneError
from prandtl_fmu.stability import StabilityWarning
from prandtl_fmu.steppers import STEPPERS
from prandtl_fmu.summary import SUMMARIES, summarize, summarize_many
from prandtl_fmu.sweep.runs import run_batch

from tests.conftest import base_tables, scene_text

STATE = ["max_abs_x", "max_abs_v", "max_abs_reaction", "final_x", "final_v", "final_reaction"]
ENERGY = ["work", "dissipated_sliders", "dissipated_damper", "dissipated"]


def random_tables(rng):
    """A random scene: effects present or not, few (O(n) kernel) or many (memory stack) branches or a
    continuum, any load; the output rows are the steps (so that simulate's rows see every step), the last one
    shorter."""
    tables = base_tables(spring={"k0": float(rng.uniform(0.1, 2))}, cubic=None, damper=None)
    if rng.random() < 0.3:
        tables["cubic"] = {"k3": float(rng.uniform(0.01, 0.2))}
    if rng.random() < 0.5:
        tables["damper"] = {"c": float(rng.uniform(0.01, 0.5))}
    massless = rng.random() < 0.25
    if massless:
        del tables["mass"]
    else:
        tables["mass"] = {"m": float(rng.uniform(0.5, 2)), "x0": float(rng.uniform(-0.2, 0.2)),
                          "v0": float(rng.uniform(-0.2, 0.2))}
    kind = rng.choice(["none", "play", "stack", "continuum", "iwan"])
    if kind == "none":
        del tables["branches"]
    elif kind == "play":
        n = int(rng.integers(1, 6))
        eta = rng.uniform(0.05, 0.5, n)
        tables["branches"] = {"k": rng.uniform(0.1, 1, n).tolist(), "eta": eta.tolist(),
                              "u0": (eta * rng.uniform(-1, 1, n)).tolist()}
    elif kind == "stack":
        tables["branches"] = {"count": int(rng.integers(64, 120)), "k_total": float(rng.uniform(0.5, 2)),
                              "eta_range": [0.05, float(rng.uniform(0.2, 0.8))]}
    elif kind == "continuum":
        tables["branches"] = {"continuum": True, "k_total": float(rng.uniform(0.5, 2)),
                              "eta_range": [0.05, float(rng.uniform(0.2, 0.8))]}
    else:
        tables["branches"] = {"continuum": True, "density": {"kind": "iwan", "F_S": float(rng.uniform(0.3, 1)),
                              "K_T": float(rng.uniform(1, 4)), "chi": -0.5, "beta": 0.2}}
    load = rng.choice(["constant", "harmonic", "table", "random"])
    if load == "constant":
        tables["load"] = {"kind": "constant", "value": float(rng.uniform(-0.3, 0.3))}
    elif load == "harmonic":
        tables["load"] = {"kind": "harmonic", "amplitude": float(rng.uniform(0.2, 1.0)),
                          "omega": float(rng.uniform(0.5, 3)), "offset": float(rng.uniform(-0.1, 0.1))}
    elif load == "table":
        times = np.sort(rng.uniform(0, 4, 5))
        tables["load"] = {"kind": "table", "time": times.tolist(), "force": rng.uniform(-0.5, 0.5, 5).tolist()}
    else:
        tables["load"] = {"kind": "random", "seed": int(rng.integers(0, 1000)), "rms": 0.3, "band": [0.5, 3.0],
                          "components": 16}
    step = float(rng.choice([0.01, 0.02]))
    tables["solver"] = {"step": step, "stop_time": 3.0 + step * rng.uniform(0.1, 0.9), "output_interval": step}
    return tables


def scene_and_stepper(rng):
    """A random scene with a random stepper that applies to it, or None (a massless continuum without a
    dashpot has none)."""
    tables = random_tables(rng)
    steppers = list(rng.permutation(list(STEPPERS)))
    for stepper in steppers:
        tables["solver"]["stepper"] = str(stepper)
        try:
            return parse_scene(scene_text(tables), "random.toml"), str(stepper)
        except SceneError:
            continue
    return None


def alone(scene, stepper):
    """The summaries from simulate's own time loop, one run alone (every step is an output row)."""
    result = simulate(scene, stepper, energy=True)
    values = {
        "max_abs_x": np.abs(result.x).max(), "max_abs_v": np.abs(result.v).max(),
        "max_abs_reaction": np.abs(result.reaction).max(), "final_x": result.x[-1], "final_v": result.v[-1],
        "final_reaction": result.reaction[-1],
    }
    e = result.energy
    values.update(work=e["work"][-1], dissipated_sliders=e["dissipated_sliders"][-1],
                  dissipated_damper=e["dissipated_damper"][-1],
                  dissipated=e["dissipated_sliders"][-1] + e["dissipated_damper"][-1])
    return values, result


@pytest.mark.slow
def test_random_scenes_of_every_structure_packed_together_equal_simulate_run_alone_bit_for_bit():
    rng = np.random.default_rng(22)  # every stepper, every branch kind, massless runs, in 8 runs
    runs = []
    while len(runs) < 8:
        drawn = scene_and_stepper(rng)
        if drawn is not None:
            runs.append(drawn)
    structures = {summary_module._Job(scene, stepper, STATE, False, None, {}).structure()
                  for scene, stepper in runs}
    assert len(structures) >= 6  # the batch mixes many structures, every branch kind among them
    assert {kind for _, _, kind, _ in structures} == {None, 1, 2, "continuum"}
    # one batch with the energy account (every stepper books it, exact exactly)
    outcomes = summarize_many(runs, STATE + ENERGY, history=True)
    assert any(stepper == "exact" for _, stepper in runs)
    for (scene, stepper), outcome in zip(runs, outcomes):
        expected, result = alone(scene, stepper)
        assert outcome.error is None, outcome.error
        for name in expected:
            assert outcome.values[name] == expected[name], (stepper, name)
        for name in ("time", "x", "v", "reaction"):
            assert np.array_equal(outcome.values[name], getattr(result, name)), (stepper, name)


def test_one_compiled_call_per_structure_and_the_cut_into_calls_changes_nothing(monkeypatch):
    document = base_tables(solver={"stepper": "verlet", "step": 0.01, "stop_time": 12.0, "output_interval": 0.5})
    scenes = []
    for j in range(30):
        tables = dict(document, load=dict(document["load"], amplitude=0.1 + 0.05 * j))
        if j % 3 == 0:
            tables["branches"] = None  # a second structure (an absent dashpot is c = 0: the same one)
        scenes.append((parse_scene(scene_text(tables)), "verlet"))
    calls = []
    run = summary_module._Batch.run

    def counted(self, outcomes, quantities):
        calls.append(len(self.jobs))
        return run(self, outcomes, quantities)

    monkeypatch.setattr(summary_module._Batch, "run", counted)
    quantities = list(SUMMARIES)
    together = summarize_many(scenes, quantities, history=True)
    assert sorted(calls) == [10, 20]
    calls.clear()
    monkeypatch.setattr(summary_module, "BATCH_BYTES", 1)  # every run its own call
    one_by_one = summarize_many(scenes, quantities, history=True)
    assert calls == [1] * 30
    for a, b in zip(together, one_by_one):
        for name in quantities:
            assert a.values[name] == b.values[name]
        assert np.array_equal(a.values["x"], b.values["x"])
    # and each run through summarize alone (a batch of one)
    for (scene, stepper), outcome in zip(scenes, together):
        single = summarize(scene, stepper, quantities)
        assert all(single[name] == outcome.values[name] for name in quantities)
    assert len({outcome.values["loop_area"] for outcome in together}) == 30


def test_a_failing_run_keeps_its_reason_and_its_neighbours_their_numbers():
    good = parse_scene(scene_text(base_tables()), "good.toml")
    collapse = parse_scene(scene_text(base_tables(mass=None, damper=None, spring=None, cubic=None,
                                                  solver={"stepper": "implicit", "step": 0.01, "stop_time": 20.0,
                                                          "output_interval": 0.1})), "collapse.toml")
    blowup = parse_scene(scene_text(base_tables(spring={"k0": 1e6}, solver={
        "stepper": "projected", "step": 0.5, "stop_time": 2000.0, "output_interval": 0.5})), "blowup.toml")
    no_loop = parse_scene(scene_text(base_tables(load={"kind": "constant", "value": 0.1})), "constant.toml")
    runs = [(good, "projected"), (collapse, "implicit"), (good, "verlet"), (blowup, "projected"),
            (no_loop, "projected"), (good, "projected")]
    outcomes = summarize_many(runs, list(SUMMARIES))
    for position in (0, 2, 5):
        assert outcomes[position].error is None
        assert outcomes[position].values == summarize(*runs[position], list(SUMMARIES))
    assert outcomes[0].values == outcomes[5].values
    with pytest.raises(ElementError) as info:
        summarize(collapse, "implicit", ["final_x"])
    assert isinstance(outcomes[1].error, ElementError) and str(outcomes[1].error) == str(info.value)
    assert "plastic collapse" in str(outcomes[1].error)
    assert isinstance(outcomes[3].error, ElementError) and "became non-finite" in str(outcomes[3].error)
    assert "beyond its stability limit" in outcomes[3].warning
    assert isinstance(outcomes[4].error, ValueError) and "loop_area needs a harmonic load" in str(outcomes[4].error)


def test_a_stability_warning_is_raised_by_summarize_and_kept_in_the_sweep_row():
    tables = base_tables(spring={"k0": 400.0},
                         solver={"stepper": "projected", "step": 0.02, "stop_time": 0.5, "output_interval": 0.1})
    with pytest.warns(StabilityWarning, match="beyond its stability limit"):
        summarize(parse_scene(scene_text(tables)), quantities=["final_x"])
    rows = run_batch(tables, "s.toml", ["solver.step"], [(0, {"solver.step": 0.02}), (1, {"solver.step": 1e-4})],
                     ["final_x"], False)
    assert "beyond its stability limit" in rows["warning"][0] and rows["warning"][1] == ""
    assert rows["error"] == ["", ""] and all(math.isfinite(value) for value in rows["final_x"])
