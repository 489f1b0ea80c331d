"""The scene format as data: every table of a scene file and every key, with its type, unit, default, bounds and
meaning.

This table is what the readers obey and what the reference says, so the two cannot part: ``scene_tables._Reader`` (and
through it ``network/model.py`` and the readers of ``memory/``) takes from here the keys a table allows, each
key's default and its bounds, and refuses to read a key that is not here (:class:`SchemaError`, a programming
error); ``docs/gen_pages.py`` writes the scene reference of the documentation site from here.

A table may have several *forms*: ``[branches]`` takes lists (``k``, ``eta``...), or ``count = n`` and a spectrum,
or the continuum, and each form allows an exact set of keys. The reader names the form once it knows it
(``only("count")``); a key read before that must mean the same in every form that has it.

What is enforced where:

* by the reader, from the fields of :class:`Key`: presence (``default``), the type, ``positive`` (> 0),
  ``minimum`` (>= minimum), ``choices``, and the magnitude of every number (a *coefficient* is 0 or has
  |value| in [1e-50, 1e50]; a *value*, ``Key.value``, only |value| <= 1e50; the ``[solver]`` times have their
  own rules): ``scene_tables.magnitude_problem``;
* by the readers' own code, and said in ``Key.rule``: what ties keys together (``alpha_kinetic <= alpha``, lists
  of equal length, ``|u0| <= eta``) and the few bounds whose refusal explains itself (``chi > -1``).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any, Optional


class SchemaError(AssertionError):
    """A reader asked for a key or a form the schema does not have, or contradicts it: a bug, never a bad scene."""


class _Marker:
    def __init__(self, name: str):
        self.name = name

    def __repr__(self) -> str:
        return self.name


REQUIRED = _Marker("REQUIRED")  # a missing key is refused
OPTIONAL = _Marker("OPTIONAL")  # a missing key is allowed; ``Key.absent`` says what its absence means


@dataclass(frozen=True)
class SameAs:
    """A default that is the value of another key of the table (``alpha_kinetic`` defaults to ``alpha``)."""

    key: str


@dataclass(frozen=True)
class Names:
    """Choices that another module registers (the steppers' names), read when first needed: the schema imports
    nothing of the package, so that every module may import it."""

    module: str  # relative to this package (".steppers")
    attribute: str
    extra: tuple = ()

    def resolve(self) -> tuple:
        # relative to this package: inside an FMU the library is a private copy under another name, and an
        # absolute "prandtl_fmu..." would load the host's installed one (or fail where there is none)
        return tuple(getattr(importlib.import_module(self.module, __package__), self.attribute)) + self.extra


# The types a key may have, and the reader's method that reads each (None: read by the reader's own code).
TYPES = {
    "number": "number", "integer": "integer", "string": "string", "boolean": "boolean",
    "list of numbers": "numbers",
    "number or list of numbers": "number numbers",
    "list of names": None,  # [network] nodes
    "pair of names": None,  # between = [i, j]
    "table": None,          # a sub-table: [mass], [branches] density = { ... }
    "list of tables": None,  # [[network.spring]]
}


@dataclass(frozen=True)
class Key:
    """One key of a table: its ``type`` (a key of TYPES), ``unit``, ``default`` (REQUIRED, OPTIONAL, a value or
    SameAs), bounds (``positive``: > 0; ``minimum``: >= minimum; ``choices``: a tuple of strings or Names),
    ``maximum`` (an integer's: <= maximum), ``value`` (a value such as an initial state, not a coefficient: only
    |value| <= 1e50), ``meaning`` (one line),
    ``rule`` (what the reader's own code checks besides) and, for an OPTIONAL key, what its absence means."""

    name: str
    type: str
    meaning: str
    unit: str = ""
    default: Any = REQUIRED
    positive: bool = False
    minimum: Optional[float] = None
    maximum: Optional[int] = None
    choices: Any = None
    value: bool = False
    rule: str = ""
    absent: str = ""

    def __post_init__(self):
        if self.type not in TYPES:
            raise SchemaError(f"{self.name}: type {self.type!r} is not one of {', '.join(TYPES)}")
        if self.default is OPTIONAL and not self.absent:
            raise SchemaError(f"{self.name}: an optional key says what its absence means")

    def choice_names(self) -> Optional[tuple]:
        """The allowed strings (None: any)."""
        return self.choices.resolve() if isinstance(self.choices, Names) else self.choices

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


@dataclass(frozen=True)
class Table:
    """One table of a scene: ``name`` its TOML path (``branches.density``, ``network.spring``), ``meaning`` (the
    effect and its equation), ``forms`` (form name -> its keys; ``""`` for a table of one form), ``choose`` (how
    the form is chosen), ``numbers``: "coefficients" (the default), "values" (every number of ``[load]``) or
    "times" (``[solver]``: rules of their own), ``source`` (where the equation comes from, for the reference) and
    ``many`` (written ``[[...]]``: any number of such tables)."""

    name: str
    meaning: str
    forms: dict
    choose: str = ""
    numbers: str = "coefficients"
    source: str = ""
    many: bool = False
    _index: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        for form, keys in self.forms.items():
            names = [key.name for key in keys]
            if len(set(names)) != len(names):
                raise SchemaError(f"[{self.name}] {form}: a key appears twice")
            for key in keys:
                self._index.setdefault(key.name, [])
                if key not in self._index[key.name]:
                    self._index[key.name].append(key)

    def keys(self, form: Optional[str] = None) -> dict:
        """The keys of ``form`` by name (``form=None``: the table's only form)."""
        if form is None:
            if len(self.forms) != 1:
                raise SchemaError(f"[{self.name}] has forms {', '.join(self.forms)}: name one")
            form = next(iter(self.forms))
        if form not in self.forms:
            raise SchemaError(f"[{self.name}] has no form {form!r} (its forms: {', '.join(map(repr, self.forms))})")
        return {key.name: key for key in self.forms[form]}

    def form_of(self, names) -> str:
        """The form whose keys are exactly ``names``."""
        for form, keys in self.forms.items():
            if {key.name for key in keys} == set(names):
                return form
        raise SchemaError(f"[{self.name}]: no form has exactly the keys {', '.join(sorted(names))}")

    def key(self, name: str, form: Optional[str] = None) -> Key:
        """The key ``name`` of ``form``; without a form, the key must mean the same in every form that has it."""
        if form is not None:
            keys = self.keys(form)
            if name not in keys:
                raise SchemaError(f"[{self.name}] {name}: not a key of the form {form!r} in the schema")
            return keys[name]
        found = self._index.get(name, [])
        if not found:
            raise SchemaError(f"[{self.name}] {name}: not a key of the schema")
        if len(found) > 1:
            raise SchemaError(f"[{self.name}] {name}: means different things in different forms: name the form")
        return found[0]

    def all_keys(self) -> list:
        """``(form, key)`` for every key of every form, in the schema's order."""
        return [(form, key) for form, keys in self.forms.items() for key in keys]


def _table(name, meaning, keys=None, *, forms=None, **options) -> Table:
    return Table(name, meaning, forms if forms is not None else {"": tuple(keys)}, **options)


# ------------------------------------------------------------------------------------------------- the keys

_STEPPERS = Names(".steppers", "STEPPERS")
_SAMPLING = Names(".effects", "SAMPLING_RULES")
_SPACINGS = Names(".masing", "SPACINGS")
# How the FMU of a scene is driven (``[fmu] causality``): "force" (force in; x, v, reaction out: the element with
# its mass, or massless) or "displacement" (the connector: x, v in; force out; massless only).
CAUSALITIES = ("force", "displacement")
ACTS_ON = ("x", "v")
SEED_RULE = "< 2^63 (a Philox key and a TOML integer)"

_INITIAL_U = Key("u0", "list of numbers", "initial elongations u_i of the branches' springs", "m", default=0.0,
                 value=True, rule="as many as the branches; |u0_i| <= eta_i")
_K_TOTAL = Key("k_total", "number", "stiffness of the spectrum: k(s) = k_total on [0, 1] (k_i = k_total / n "
               "sampled)", "N/m", positive=True)
_ETA_RANGE = Key("eta_range", "list of numbers", "[a, b]: elastic ranges eta(s) = a + (b - a) s, s in [0, 1]", "m",
                 minimum=0.0, rule="two numbers; a < b for the continuum")
_COUNT = Key("count", "integer", "number n of sampled branches", minimum=1,
             rule="n branches must fit in the memory available")
_SHARED_DASHPOT = Key("c", "number", "a dashpot in series with every branch's spring and slider (the series "
                      "model): rate-dependent hysteresis", "N s/m", default=OPTIONAL, positive=True,
                      absent="no series dashpots", rule="one number for every branch (not a list)")
_CONTINUUM = Key("continuum", "boolean", "true: infinitely many branches s in [0, 1], the continuous element (of "
                 "k_total and eta_range, or of a density); it starts virgin", default=False,
                 rule="no series dashpots (sample it with count = n); false: as if absent")
_DENSITY = Key("density", "table", "the spectrum: `{ kind = \"iwan\", ... }` or `{ kind = \"piecewise\", ... }` "
               "([branches.density])")

_NOISE = (
    Key("noise_intensity", "number", "sigma of a white noise added to the force: F(t) + sigma xi(t)", "N sqrt(s)",
        default=OPTIONAL, minimum=0.0, absent="no noise (0 too)"),
    Key("noise_seed", "integer", "the Brownian path's key", default=OPTIONAL, minimum=0,
        absent="required with noise_intensity", rule=f"{SEED_RULE}; only with noise_intensity"),
    Key("noise_unit", "number", "the Brownian tree's time unit: a property of the path, not of the step; the "
        "coarsest step is a good choice", "s", default=1.0, positive=True,
        rule="the step >= 2^-40 units, stop_time <= 2^52 units; only with a noise (noise_intensity, or the "
             "white_noise kind)"),
)
_LOAD_KIND = Key("kind", "string", "the force history", choices=("harmonic", "constant", "table", "random",
                                                                  "white_noise"))
_OFFSET = Key("offset", "number", "constant force added", "N", default=0.0)
_SEED = Key("seed", "integer", "the seed: the force is a function of it alone", minimum=0, rule=SEED_RULE)

_BETWEEN = Key("between", "pair of names", "the two ends: node names, or a node and \"ground\"",
               rule="two different ends; the ground is the second end internally")
_ELEMENT_NAME = Key("name", "string", "the element's name (FMU parameters <coefficient>_<name>)", default=OPTIONAL,
                    absent="<kind>_<index>: spring_1, spring_2, ...",
                    rule="letters, digits and _ (not first a digit); unique among nodes and elements; not \"ground\"")
_ACTS_ON = Key("acts_on", "string", "the state the memory reads: y = x or v", default="x", choices=ACTS_ON,
               rule="\"v\" needs [mass]")


SCHEMA = {table.name: table for table in (
    _table("scene", "the top level of a scene file: its name and tables; an absent table is an absent effect, "
           "which costs nothing", forms={
               "element": (
                   Key("name", "string", "free text: the scene's name (the FMU's modelName)", default=OPTIONAL,
                       absent="the file name without .toml"),
                   Key("mass", "table", "inertia", default=OPTIONAL, absent="the massless element"),
                   Key("friction", "table", "friction of the mass on the ground", default=OPTIONAL, absent="none"),
                   Key("spring", "table", "linear spring", default=OPTIONAL, absent="none"),
                   Key("cubic", "table", "cubic spring", default=OPTIONAL, absent="none"),
                   Key("damper", "table", "viscous dashpot", default=OPTIONAL, absent="none"),
                   Key("branches", "table", "Prandtl branches", default=OPTIONAL, absent="none"),
                   Key("masing", "table", "a backbone curve, as branches and a spring", default=OPTIONAL,
                       absent="none", rule="not with [branches] or [spring]"),
                   Key("load", "table", "the force F(t) of a standalone run", default=OPTIONAL, absent="F = 0"),
                   Key("solver", "table", "the time discretisation"),
                   Key("fmu", "table", "how the scene's FMU is driven", default=OPTIONAL, absent="causality "
                       "\"force\""),
                   Key("delay", "table", "a delayed force", default=OPTIONAL, absent="none"),
                   Key("history", "table", "a convolution (history) force", default=OPTIONAL, absent="none"),
                   Key("dahl", "table", "Dahl's friction on the mass", default=OPTIONAL, absent="none",
                       rule="not with [friction]"),
               ),
               "network": (
                   Key("name", "string", "free text: the scene's name (the FMU's modelName)", default=OPTIONAL,
                       absent="the file name without .toml"),
                   Key("network", "table", "nodes and the elements between them", default=OPTIONAL,
                       absent="give [network] or [chain]"),
                   Key("chain", "table", "the chain on a fixed support (shorthand of [network])", default=OPTIONAL,
                       absent="give [network] or [chain]", rule="not with [network]"),
                   Key("load", "table", "the force F(t) on the load node", default=OPTIONAL, absent="F = 0"),
                   Key("solver", "table", "the time discretisation"),
                   Key("fmu", "table", "how the scene's FMU is driven", default=OPTIONAL,
                       absent="causality \"force\""),
               )},
           choose="a scene with [network] or [chain] is a network; any other scene is an element"),

    _table("mass", "inertia: m x'' = F - (the other forces). Without [mass], the massless element: x(0) = 0, "
           "quasi-static (with a dashpot: c x' = F - the other forces)", [
               Key("m", "number", "mass", "kg", positive=True),
               Key("x0", "number", "initial displacement", "m", default=0.0, value=True),
               Key("v0", "number", "initial velocity", "m/s", default=0.0, value=True),
           ]),
    _table("friction", "friction of the mass on the ground: m v' + A(v - v_b) ∋ F - ..., A(w) = alpha sigma(w) + "
           "sign(w) (alpha_kinetic - alpha) (1 - exp(-|w| / stribeck_velocity)), sigma the sign graph", [
               Key("alpha", "number", "static threshold alpha_S", "N", positive=True),
               Key("alpha_kinetic", "number", "sliding force at speed (Stribeck)", "N", default=SameAs("alpha"),
                   minimum=0.0, rule="<= alpha; < alpha needs stribeck_velocity"),
               Key("stribeck_velocity", "number", "slip speed over which the sliding force falls from alpha to "
                   "alpha_kinetic", "m/s", default=OPTIONAL, positive=True,
                   absent="plain Coulomb friction (required when alpha_kinetic < alpha)"),
               Key("belt_velocity", "number", "speed v_b of the ground (a belt); the friction acts on the slip "
                   "v - v_b", "m/s", default=0.0, value=True),
           ], source="the slides of the related models (004 in the papers' list), eq. 14 (the parallel model) and 16 "
                     "(Stribeck)"),
    _table("spring", "linear spring in parallel: force k0 x", [
        Key("k0", "number", "stiffness", "N/m", minimum=0.0)]),
    _table("cubic", "cubic spring in parallel: force k3 x^3", [
        Key("k3", "number", "coefficient", "N/m^3", minimum=0.0)]),
    _table("damper", "viscous dashpot in parallel: force c v (c = 0 is no dashpot)", [
        Key("c", "number", "dashpot coefficient", "N s/m", minimum=0.0)]),
    _table("branches", "Prandtl branches: spring k_i in series with a Coulomb slider of threshold alpha_i = k_i "
           "eta_i, u_i' + d psi_[-eta_i, eta_i](u_i) ∋ v (with a series dashpot c_i: ∋ v - (k_i / c_i) u_i); "
           "force sum_i k_i u_i", forms={
               "lists": (
                   Key("k", "list of numbers", "stiffnesses k_i, one per branch", "N/m", positive=True),
                   Key("eta", "list of numbers", "elastic ranges eta_i = alpha_i / k_i", "m", default=OPTIONAL,
                       minimum=0.0, absent="give eta or alpha", rule="as many as k; not with alpha"),
                   Key("alpha", "list of numbers", "slip thresholds alpha_i (eta_i = alpha_i / k_i)", "N",
                       default=OPTIONAL, minimum=0.0, absent="give eta or alpha", rule="as many as k; not with eta"),
                   _INITIAL_U,
                   Key("c", "list of numbers", "dashpots in series with each branch's spring and slider (the series "
                       "model): rate-dependent hysteresis", "N s/m", default=OPTIONAL, positive=True,
                       absent="no series dashpots", rule="as many as k"),
               ),
               "count": (_COUNT, _K_TOTAL, _ETA_RANGE, _INITIAL_U,
                         Key("sampling", "string", "where eta(s) is sampled in each of the n cells: \"right\" "
                             "eta(i / n) (eq. 7.19), \"midpoint\" eta((i - 1/2) / n)", default="right",
                             choices=_SAMPLING),
                         _SHARED_DASHPOT),
               "continuum": (_CONTINUUM, _K_TOTAL, _ETA_RANGE),
               "density continuum": (_CONTINUUM, _DENSITY),
               "density count": (
                   _COUNT, _DENSITY,
                   Key("sampling", "string", "how each cell's eta_i is taken: \"mean\" its stiffness-weighted "
                       "mean (keeps each segment's stiffness and strength), \"midpoint\", \"right\"",
                       default="mean", choices=Names(".effects", "SAMPLING_RULES", ("mean",))),
                   _SHARED_DASHPOT),
           },
           choose="by the keys given: lists (k with eta or alpha); count = n with k_total and eta_range (the "
                  "paper's spectrum, sampled); continuum = true with k_total and eta_range; a density, with "
                  "continuum = true or count = n",
           source="Bastien & Schatzman, M2AN 36 (2002), eq. (7.7) and (7.19); series dashpots: eq. 15 "
                  "of the slides of the related models (004)"),
    _table("branches.density", "a spectrum of branches s in [0, 1]: stiffness density k(s), elastic range eta(s) "
           "(docs/spectra.md)", forms={
               "iwan": (
                   Key("kind", "string", "the family of the spectrum", choices=("iwan", "piecewise")),
                   Key("F_S", "number", "force at macro-slip", "N", positive=True),
                   Key("K_T", "number", "stiffness while everything sticks", "N/m", positive=True),
                   Key("chi", "number", "power of the density of slider strengths phi^chi (Segalman: -1 < chi < 0)",
                       rule="> -1 (the density must be integrable at 0)"),
                   Key("beta", "number", "weight of the Dirac at phi_max", minimum=0.0),
               ),
               "piecewise": (
                   Key("kind", "string", "the family of the spectrum", choices=("iwan", "piecewise")),
                   Key("s", "list of numbers", "segment ends in s", default=OPTIONAL,
                       absent="equal segments", rule="one more than k; from 0 to 1, rising strictly"),
                   Key("k", "list of numbers", "stiffness density k(s) on each segment", "N/m per unit of s",
                       minimum=0.0, rule="not all 0"),
                   Key("eta", "list of numbers", "eta(s) at the segment ends, linear between", "m", minimum=0.0,
                       rule="one more than k; non-decreasing"),
               )},
           choose="by `kind`", source="Segalman, J. Appl. Mech. 72 (2005): the four-parameter Iwan model"),
    _table("masing", "a Masing model given by its backbone F_b(x), turned into the branches of its Iwan spectrum "
           "and the parallel spring k0 = F_b'(inf) (docs/masing.md)", forms={
               "bilinear": (
                   Key("kind", "string", "the backbone", choices=("bilinear", "hyperbolic", "ramberg_osgood")),
                   Key("k", "number", "initial stiffness", "N/m", positive=True),
                   Key("f_y", "number", "yield force", "N", positive=True),
                   Key("alpha", "number", "post-yield stiffness ratio", default=0.0, minimum=0.0, rule="< 1"),
               ),
               "hyperbolic": (
                   Key("kind", "string", "the backbone", choices=("bilinear", "hyperbolic", "ramberg_osgood")),
                   Key("k", "number", "initial stiffness", "N/m", positive=True),
                   Key("f_u", "number", "ultimate force: F_b(x) = k x / (1 + k |x| / f_u)", "N", positive=True),
                   Key("count", "integer", "number of branches", default=100, minimum=1),
                   Key("x_max", "number", "the last node: the largest |x| the element will see", "m", positive=True),
                   Key("spacing", "string", "nodes at equal steps of F_b (\"force\") or of x (\"displacement\")",
                       default="force", choices=_SPACINGS),
               ),
               "ramberg_osgood": (
                   Key("kind", "string", "the backbone", choices=("bilinear", "hyperbolic", "ramberg_osgood")),
                   Key("k", "number", "initial stiffness", "N/m", positive=True),
                   Key("f_y", "number", "reference force: x = F / k (1 + a |F / f_y|^(r - 1))", "N", positive=True),
                   Key("a", "number", "the Ramberg-Osgood coefficient", positive=True),
                   Key("r", "number", "the Ramberg-Osgood exponent", rule="> 1"),
                   Key("count", "integer", "number of branches", default=100, minimum=1),
                   Key("x_max", "number", "the last node: the largest |x| the element will see", "m", positive=True),
                   Key("spacing", "string", "nodes at equal steps of F_b (\"force\") or of x (\"displacement\")",
                       default="force", choices=_SPACINGS),
               )},
           choose="by `kind`", source="Masing (1926); Iwan, J. Appl. Mech. 33 (1966)"),
    _table("load", "the force F(t) on the element (a network's load node) in a standalone run", forms={
        "harmonic": (_LOAD_KIND, Key("amplitude", "number", "F(t) = offset + amplitude cos(omega t)", "N"),
                     Key("omega", "number", "angular frequency", "rad/s"), _OFFSET) + _NOISE,
        "constant": (_LOAD_KIND, Key("value", "number", "F(t) = value", "N")) + _NOISE,
        "table": (_LOAD_KIND,
                  Key("time", "list of numbers", "time points; F linear between them, held at force[1] before "
                      "and at the last value after", "s", minimum=0.0,
                      rule="non-decreasing; a time at most twice (a jump)"),
                  Key("force", "list of numbers", "F at each time point", "N", rule="as many as time")) + _NOISE,
        "random": (_LOAD_KIND, _SEED,
                   Key("rms", "number", "standard deviation of F (band-limited Gaussian noise)", "N", minimum=0.0),
                   Key("band", "list of numbers", "[omega_min, omega_max]: the band of the flat spectrum", "rad/s",
                       minimum=0.0, rule="two numbers, omega_min < omega_max"),
                   Key("components", "integer", "number of cosines", default=100, minimum=1), _OFFSET) + _NOISE,
        "white_noise": (_LOAD_KIND,
                        Key("intensity", "number", "sigma: F(t) = offset + sigma xi(t), xi a standard white noise "
                            "(0: F = offset)", "N sqrt(s)", minimum=0.0),
                        Key("seed", "integer", "the Brownian path's key", minimum=0, rule=SEED_RULE),
                        _OFFSET, _NOISE[2]),
    }, choose="by `kind`", numbers="values",
        source="white noise: Lamarque, Bernardin & Bastien (2005) (docs/white-noise.md)"),
    _table("solver", "the time discretisation: step p is taken at t_p = p h", [
        Key("stepper", "string", "the scheme", default="projected", choices=_STEPPERS,
            rule="must apply to the scene (docs: Steppers)"),
        Key("step", "number", "internal time step h", "s", positive=True, rule=">= 1e-150; at most 2^53 steps"),
        Key("stop_time", "number", "end of a run", "s", positive=True, rule=">= 1e-150"),
        Key("output_interval", "number", "time between output rows (the FMU's default communication step)", "s",
            positive=True, rule="a whole multiple of step"),
    ], numbers="times"),
    _table("fmu", "how the scene's FMU is driven", [
        Key("causality", "string", "\"force\": F in; x, v, reaction out (the element). \"displacement\": the "
            "connector between two bodies: x, v in; force out", default="force", choices=CAUSALITIES,
            rule="\"displacement\": no [mass] (a network: a massless load node)"),
    ]),
    _table("delay", "a delayed force on the mass: -gain y(t - tau), y = x or v; y(s) = y(0) for s < 0", [
        Key("gain", "number", "gain (either sign)", "N/m on x, N s/m on v",
            rule="a negative gain: refused on a massless element without a dashpot, and with tau < step"),
        Key("tau", "number", "the delay", "s", positive=True,
            rule="its buffer, about tau / step values, must fit in the memory available (and hold at most 2^31)"),
        _ACTS_ON,
    ], source="Lamarque, Bastien & Holland, SIAM J. Numer. Anal. 41 (2003) (docs/memory.md)"),
    _table("history", "a convolution force on the mass: -int_0^t sum_j weight_j exp(-rate_j (t - s)) y(s) ds", [
        Key("weight", "list of numbers", "the kernel's weights (either sign)", "N/(m s) on x, N/m on v",
            rule="at least one term; a negative one: refused on a massless element without a dashpot"),
        Key("rate", "list of numbers", "the kernel's rates (0: a plain integral)", "1/s", minimum=0.0,
            rule="as many as weight"),
        _ACTS_ON,
    ], source="Bastien & Lamarque, Nonlinear Analysis 63 (2005) (docs/memory.md)"),
    _table("dahl", "Dahl's friction on the mass: -F_d, dF_d/dt = sigma (1 - F_d / F_c sgn v)^exponent v, "
           "F_d(0) = 0", [
               Key("sigma", "number", "stiffness at a reversal", "N/m", positive=True),
               Key("force", "number", "the Coulomb level F_c it approaches", "N", positive=True),
               Key("exponent", "number", "the exponent", default=1.0, positive=True,
                   rule="<= memory.dahl.MAX_EXPONENT"),
               Key("kind", "string", "the law (\"envelope\", the modified model, is refused)", default="dahl",
                   choices=("dahl",)),
           ], source="Dahl, AIAA J. 14 (1976); in the form of Olsson et al., Eur. J. Control 4 (1998), eq. 6"),
    _table("network", "nodes with masses, and elements between two nodes or a node and the ground "
           "(docs/networks.md)", [
               Key("nodes", "list of names", "node names", rule="letters, digits and _ (not first a digit); "
                   "unique; \"ground\" is reserved"),
               Key("mass", "list of numbers", "mass of each node (0: a massless node, quasi-static)", "kg",
                   minimum=0.0, rule="one per node"),
               Key("x0", "list of numbers", "initial displacements", "m", default=0.0, value=True,
                   rule="one per node; a massless node starts in equilibrium with F(0)"),
               Key("v0", "list of numbers", "initial velocities", "m/s", default=0.0, value=True,
                   rule="one per node (ignored for a massless node)"),
               Key("load_node", "string", "the node the load (the FMU's input) acts on", default=OPTIONAL,
                   absent="the last node", rule="one of the nodes"),
               Key("spring", "list of tables", "[[network.spring]]", default=OPTIONAL, absent="none"),
               Key("dashpot", "list of tables", "[[network.dashpot]]", default=OPTIONAL, absent="none"),
               Key("slider", "list of tables", "[[network.slider]]", default=OPTIONAL, absent="none"),
               Key("branch", "list of tables", "[[network.branch]]", default=OPTIONAL, absent="none"),
               Key("cubic", "list of tables", "[[network.cubic]]", default=OPTIONAL, absent="none"),
           ], source="Bastien & Lamarque, Math. Probl. Eng. (2009) for the chain (docs/networks.md)"),
    _table("network.spring", "a linear spring between two ends: force k (x_i - x_j)", [
        _BETWEEN, _ELEMENT_NAME, Key("k", "number", "stiffness", "N/m", minimum=0.0)], many=True),
    _table("network.dashpot", "a dashpot between two ends: force c (v_i - v_j)", [
        _BETWEEN, _ELEMENT_NAME, Key("c", "number", "dashpot coefficient", "N s/m", minimum=0.0)], many=True),
    _table("network.slider", "a Saint-Venant slider between two ends: force in alpha sign(v_i - v_j) ([-alpha, "
           "alpha] while it sticks)", [
               _BETWEEN, _ELEMENT_NAME, Key("alpha", "number", "threshold", "N", minimum=0.0)], many=True),
    _table("network.branch", "a Prandtl branch between two ends, the element's: spring k in series with a slider "
           "of threshold k eta (and a dashpot c: the series model); force k u", [
               _BETWEEN, _ELEMENT_NAME,
               Key("k", "number", "stiffness", "N/m", positive=True),
               Key("eta", "number", "elastic range", "m", minimum=0.0),
               Key("c", "number", "a dashpot in series", "N s/m", default=OPTIONAL, positive=True,
                   absent="no series dashpot"),
               Key("u0", "number", "initial elongation (of x_i - x_j)", "m", default=0.0, value=True,
                   rule="|u0| <= eta"),
           ], many=True),
    _table("network.cubic", "a cubic spring between two ends: force k3 (x_i - x_j)^3", [
        _BETWEEN, _ELEMENT_NAME, Key("k3", "number", "coefficient", "N/m^3", minimum=0.0)], many=True),
    _table("chain", "the chain sliding on a fixed support: nodes n1 .. n<n>, springs between neighbours, a slider "
           "of each node on the support, the load on the last node", [
               Key("n", "integer", "number of nodes", minimum=1, maximum=10_000_000),
               Key("m", "number or list of numbers", "mass of each node (0: the quasi-static chain)", "kg",
                   minimum=0.0, rule="a list: one per node"),
               Key("k", "number or list of numbers", "springs between neighbours", "N/m", default=OPTIONAL,
                   minimum=0.0, absent="required when n > 1 (none when n = 1)",
                   rule="> 0; a list: n - 1 values"),
               Key("alpha", "number or list of numbers", "each node's slider on the support", "N", minimum=0.0,
                   rule="a list: one per node"),
               Key("c", "number or list of numbers", "each node's dashpot to the support", "N s/m",
                   default=OPTIONAL, minimum=0.0, absent="no dashpots", rule="a list: one per node"),
               Key("k_wall", "number", "a spring from n1 to the ground (the wall)", "N/m", default=OPTIONAL,
                   positive=True, absent="no wall spring"),
           ], source="Bastien & Lamarque, Math. Probl. Eng. (2009)"),
)}


def table(name: str) -> Table:
    """The table ``name`` of the schema (SchemaError if there is none)."""
    try:
        return SCHEMA[name]
    except KeyError:
        raise SchemaError(f"[{name}]: not a table of the schema") from None


def top_level(kind: str) -> frozenset:
    """The keys allowed at the top level of an ``"element"`` or a ``"network"`` scene."""
    return frozenset(SCHEMA["scene"].keys(kind))

