"""White noise on the element's load (issue 34): the scene's keys, the path, the schemes against an independent
implementation, and the exact stationary laws of the mechanics.

The laws (independent of the code):

* m x'' + c x' + k x = sigma xi: <x^2> = sigma^2 / (2 c k), <v^2> = sigma^2 / (2 c m);
* with a cubic spring k3 and no sliders, the Gibbs law p(x, v) ∝ exp(-(2 c / sigma^2) (m v^2/2 + k x^2/2 + k3 x^4/4));
* a free mass with a dashpot and Coulomb friction on the ground, m v' = -c v - alpha sign(v) + sigma xi:
  p(v) ∝ exp(-(2 m / sigma^2) (c v^2 / 2 + alpha |v|)) (Fokker-Planck of dv = -(c v + alpha sign v)/m dt +
  (sigma/m) dW). The diffusion sigma/m does not vanish at v = 0, so the velocity has no atom there: the mass
  never sticks (P(v = 0) = 0) as long as sigma > 0. The implicit scheme sticks exactly (v1 = 0) when
  |m v + sigma dW| <= alpha h, which has probability 2 alpha h p(0) / m + o(h): an atom of the scheme, O(h).

Every statistical check bounds the time average's error by its standard deviation (derived, or estimated by
batch means) plus the scheme's O(h) bias (measured with the same path at h and h/2: the tree makes their
difference nearly free of sampling noise).
"""
import math

import numpy as np
import pytest

from prandtl_fmu import Element, simulate
from prandtl_fmu.driver import simulate_chunks
from prandtl_fmu.loads import ConstantLoad, WhiteNoise, impulse, tree_time
from prandtl_fmu.noise import increment, new_cache
from prandtl_fmu.scene import SceneError, load_scene, parse_scene


def toml_of(tables: dict) -> str:
    """A scene's TOML from {table: {key: value}} (top-level keys under "")."""
    lines = [f"{key} = {value!r}".replace("'", '"') for key, value in tables.get("", {}).items()]
    for table, keys in tables.items():
        if table == "":
            continue
        lines.append(f"[{table}]")
        for key, value in keys.items():
            text = repr(value).replace("'", '"') if not isinstance(value, bool) else str(value).lower()
            lines.append(f"{key} = {text}")
    return "\n".join(lines) + "\n"


def scene_of(tables: dict, source="<test>"):
    return parse_scene(toml_of(tables), source)


def oscillator(m=1.0, k=1.0, c=1.0, sigma=1.0, seed=1, h=2.0 ** -7, stop=10.0, interval=None, stepper="implicit",
               unit=1.0, extra=None):
    tables = {"": {"name": "noisy"}, "mass": {"m": m}, "spring": {"k0": k}, "damper": {"c": c},
              "load": {"kind": "white_noise", "intensity": sigma, "seed": seed, "noise_unit": unit},
              "solver": {"stepper": stepper, "step": h, "stop_time": stop, "output_interval": interval or h}}
    for table, keys in (extra or {}).items():
        tables.setdefault(table, {}).update(keys)
    return tables


# --- the scene's keys: one line naming the culprit ------------------------------------------------------------

REFUSED = {
    "negative intensity": ({"load": {"intensity": -1.0}}, "[load] intensity: must be >= 0"),
    "infinite intensity": ({"load": {"intensity": math.inf}}, "[load] intensity: must be finite"),
    "non-integer seed": ({"load": {"seed": 1.5}}, "[load] seed: must be an integer"),
    "negative seed": ({"load": {"seed": -1}}, "[load] seed: must be >= 0"),
    "seed beyond 2^63": ({"load": {"seed": 2 ** 63}}, "[load] seed: must be < 2^63"),
    "zero unit": ({"load": {"noise_unit": 0.0}}, "[load] noise_unit: must be > 0"),
    "unknown key": ({"load": {"intensty": 1.0}}, "[load] intensty: unknown key"),
    "noise keys on white_noise": ({"load": {"noise_intensity": 1.0}}, "[load] noise_intensity: a white_noise load is"),
    "verlet": ({"solver": {"stepper": "verlet"}}, "[solver] stepper: 'verlet' takes no white noise"),
    "symplectic": ({"solver": {"stepper": "symplectic"}}, "[solver] stepper: 'symplectic' takes no white noise"),
    "exact": ({"solver": {"stepper": "exact"}}, "[solver] stepper: 'exact' has no exact solution under a white noise"),
}


@pytest.mark.parametrize("case", list(REFUSED))
def test_white_noise_scene_refused_in_one_line(case):
    changes, message = REFUSED[case]
    with pytest.raises(SceneError) as raised:
        scene_of(oscillator(extra=changes))
    text = str(raised.value)
    assert "\n" not in text and text.startswith("<test>: ") and message in text, text


def test_noise_keys_on_a_deterministic_load():
    base = {"": {"name": "n"}, "mass": {"m": 1.0}, "solver": {"stepper": "implicit", "step": 0.01, "stop_time": 1.0,
                                                              "output_interval": 0.1}}
    load = {"kind": "harmonic", "amplitude": 1.0, "omega": 2.0, "noise_intensity": 0.5, "noise_seed": 9}
    scene = scene_of({**base, "load": load})
    assert scene.load.noise == WhiteNoise(0.5, 9, 1.0) and scene.load.amplitude == 1.0
    for changed, message in (({"noise_intensity": None}, "[load] noise_seed: needs noise_intensity"),
                             ({"noise_seed": None}, "[load] noise_seed: missing"),
                             ({"noise_intensity": -0.5}, "[load] noise_intensity: must be >= 0"),
                             ({"noise_unit": -1.0}, "[load] noise_unit: must be > 0")):
        tables = {**base, "load": {key: value for key, value in {**load, **changed}.items() if value is not None}}
        with pytest.raises(SceneError) as raised:
            scene_of(tables)
        assert message in str(raised.value) and "\n" not in str(raised.value), str(raised.value)
    # sigma = 0 is no noise at all: the deterministic load, every stepper
    tables = {**base, "load": {**load, "noise_intensity": 0.0}, "solver": {**base["solver"], "stepper": "verlet"}}
    assert scene_of(tables).load.noise is None


def test_massless_element_without_dashpot_is_refused():
    tables = {"": {"name": "n"}, "spring": {"k0": 1.0},
              "load": {"kind": "white_noise", "intensity": 1.0, "seed": 1},
              "solver": {"stepper": "implicit", "step": 0.01, "stop_time": 1.0, "output_interval": 0.1}}
    with pytest.raises(SceneError, match="massless element without a dashpot has no solution"):
        scene_of(tables)
    tables["damper"] = {"c": 1.0}
    assert scene_of(tables).load.noise is not None  # with a dashpot: c dx = ... dt + sigma dB


# --- the path: a function of (seed, time) -----------------------------------------------------------------------


def test_tree_time_puts_step_times_on_the_tree():
    """t_p = p h computed in doubles, h = T0 / 2^j for a unit T0 that is not a double (1e-3 s, 0.1 s): the point
    of the tree is p / 2^j exactly (one normal per step), and h and h / 2 share their points."""
    for unit in (1e-3, 0.1, 1.0, 3.0):
        for j in (0, 1, 3):
            h = unit / 2 ** j
            p = np.arange(0, 200_001, 997)
            tau = np.array([tree_time(q * h, unit) for q in p.tolist()])
            assert np.array_equal(tau, p / 2.0 ** j), (unit, j)
    # monotone: adjacent steps' increments add up, whatever the times
    times = np.sort(np.random.default_rng(0).uniform(0, 1e4, 2000))
    tau = np.array([tree_time(t, 0.1) for t in times.tolist()])
    assert np.all(np.diff(tau) >= 0)


def test_impulse_is_additive_and_scaled():
    """B = sqrt(T0) W(t / T0): a step's impulse is sigma sqrt(T0) times the tree's increment, whose halves add up
    to it bit for bit (the impulse, scaled once, to rounding)."""
    unit = 0.1
    load = ConstantLoad(0.0, WhiteNoise(2.0, 11, unit)).compile()
    h = unit / 8
    cache = new_cache()
    for p in (0, 5, 1234):
        whole = increment(11, p / 8, (p + 1) / 8, cache)
        assert whole == increment(11, p / 8, (2 * p + 1) / 16, cache) + increment(11, (2 * p + 1) / 16, (p + 1) / 8,
                                                                                 cache)
        assert impulse(load, p * h, h) == 2.0 * math.sqrt(unit) * whole
        halves = impulse(load, p * h, h / 2) + impulse(load, (2 * p + 1) * (h / 2), h / 2)
        assert halves == pytest.approx(2.0 * math.sqrt(unit) * whole, rel=1e-15, abs=1e-300)
