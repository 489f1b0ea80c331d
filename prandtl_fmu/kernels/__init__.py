"""Compiled building blocks shared by the steppers.

``smooth`` holds the forces of the single-valued effects (springs, dashpot),
``play`` the friction branches. Every function takes ``None`` for an absent
effect; numba compiles one specialisation per set of present effects and
prunes the ``is None`` tests, so an absent effect leaves no code behind.
"""
