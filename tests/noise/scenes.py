"""The scenes the tests of the white noise share (the PythonFMU and the native FMU run the same element)."""


def noisy_element(stop_time: float) -> str:
    """A mass, a spring, a dashpot and two branches under a harmonic load with a white noise on it."""
    return NOISY_ELEMENT.format(stop_time=stop_time)


NOISY_ELEMENT = """name = "noisy-element"

[mass]
m = 1.0

[spring]
k0 = 1.0

[damper]
c = 0.2

[branches]
k = [0.5, 0.3]
eta = [0.1, 0.4]

[load]
kind = "harmonic"
amplitude = 0.5
omega = 1.1
noise_intensity = 0.4
noise_seed = 7
noise_unit = 0.01

[solver]
stepper = "implicit"
step = 0.005
stop_time = {stop_time}
output_interval = 0.1
"""
