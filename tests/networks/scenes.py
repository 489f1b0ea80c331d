"""The networks the native FMU's tests build (tests/networks/test_native.py, and the native tests that need a
network: tests/fmu/native/test_chosen_steppers.py, test_platforms.py), as scene texts by name."""

SCENES = {
    # a chain of three masses on a support (sliders, dashpots) held by a wall spring
    "chain3": """
name = "chain3"

[chain]
n = 3
m = [0.5, 0.4, 0.3]
k = 200.0
alpha = [0.8, 0.5, 0.3]
c = 0.05
k_wall = 100.0

[load]
kind = "harmonic"
amplitude = 2.0
omega = 7.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.01
""",
    # a massless chain with a dashpot at every node (the equilibrium at t = 0 has rigid dashpots)
    "massless": """
name = "massless"

[chain]
n = 3
m = 0.0
k = 1.0
alpha = 0.5
c = 0.2
k_wall = 1.0

[load]
kind = "harmonic"
amplitude = 1.2
omega = 1.0

[solver]
stepper = "implicit"
step = 0.01
stop_time = 5.0
output_interval = 0.1
""",
    # a Prandtl branch (series dashpot, u0) and a slider between two masses; c held by a slider and a branch
    "joint": """
name = "joint"

[network]
nodes = ["a", "b", "c"]
mass = [1.0, 2.0, 0.5]
x0 = [0.01, 0.0, 0.0]
load_node = "a"

[[network.spring]]
between = ["a", "ground"]
k = 100.0

[[network.spring]]
between = ["b", "ground"]
k = 400.0

[[network.slider]]
between = ["a", "b"]
alpha = 2.0

[[network.branch]]
between = ["a", "b"]
k = 50.0
eta = 0.02
u0 = 0.005
c = 5.0

[[network.slider]]
between = ["c", "b"]
alpha = 0.3

[[network.branch]]  # towards the ground: kept on x_c, its elongation as written is -x_c (Element.sense)
between = ["c", "ground"]
k = 20.0
eta = 0.01
u0 = 0.004

[[network.dashpot]]
between = ["b", "ground"]
c = 0.5

[[network.cubic]]
between = ["a", "ground"]
k3 = 10000.0

[load]
kind = "harmonic"
amplitude = 10.0
omega = 5.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 2.0
output_interval = 0.01
""",
    # every node massive, all plasticity in branches: projected applies too
    # b held by a slider alone: massless, it is refused
    "slider_held": """
name = "slider_held"

[network]
nodes = ["a", "b"]
mass = [1.0, 0.5]
load_node = "a"

[[network.spring]]
between = ["a", "ground"]
k = 10.0

[[network.slider]]
between = ["a", "b"]
alpha = 0.4

[load]
kind = "harmonic"
amplitude = 1.0
omega = 2.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.1
""",
    "branches": """
name = "branches"

[network]
nodes = ["p", "q"]
mass = [1.0, 0.5]
v0 = [0.2, 0.0]

[[network.branch]]
between = ["p", "ground"]
k = 80.0
eta = 0.01

[[network.branch]]
between = ["p", "q"]
k = 40.0
eta = 0.02
c = 3.0

[[network.spring]]
between = ["q", "ground"]
k = 30.0

[[network.cubic]]
between = ["q", "p"]
k3 = 500.0

[load]
kind = "harmonic"
amplitude = 3.0
omega = 6.0

[solver]
stepper = "projected"
step = 0.0005
stop_time = 1.0
output_interval = 0.01
""",
    # one node on a spring and a branch beside it (issue 59: a node that falls by decades in one step; a mass)
    "one_node": """
name = "one_node"

[network]
nodes = ["a"]
mass = [0.0]
load_node = "a"

[[network.spring]]
between = ["a", "ground"]
k = 1.0

[[network.branch]]
between = ["a", "ground"]
k = 1.0
eta = 1.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.001
""",
    # a soft ground spring beside a stiff one (issue 59: the pivots of a large stiffness contrast)
    "contrast": """
name = "contrast"

[network]
nodes = ["a", "b"]
mass = [0.0, 0.0]
load_node = "b"

[[network.spring]]
between = ["a", "ground"]
k = 1e-14

[[network.branch]]
between = ["a", "ground"]
k = 1.0
eta = 1.0

[[network.spring]]
between = ["a", "b"]
k = 1.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.001
""",
}
