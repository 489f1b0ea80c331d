"""The scenes the tests of the effects with memory share (the PythonFMU and the native FMU run the same one)."""

# every effect with memory, the history on v: the element both FMU runtimes are checked on
EVERY_EFFECT = """name = "memory-element"

[mass]
m = 0.8
x0 = 0.1

[spring]
k0 = 5.0

[branches]
k = [2.0, 1.0]
alpha = [0.1, 0.3]

[delay]
gain = 0.7
tau = 0.023

[history]
weight = [0.4, -0.1]
rate = [1.3, 0.0]
acts_on = "v"

[dahl]
sigma = 30.0
force = 0.2

[load]
kind = "harmonic"
amplitude = 1.0
omega = 3.0

[solver]
stepper = "implicit"
step = 0.001
stop_time = 1.0
output_interval = 0.01
"""
