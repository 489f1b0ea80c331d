"""Compiled building blocks shared by the steppers.

``smooth`` holds the forces of the single-valued effects (springs, dashpot);
``play`` the friction branches, one update per branch, and the dispatch to
``stack``, the memory stack (O(1) per move for many branches, and the continuum); ``increment``
the scalar equation of an implicit step; ``energy`` the energy account. Every function takes ``None`` for an absent
effect; numba compiles one specialisation per set of present effects and
prunes the ``is None`` tests, so an absent effect leaves no code behind.
"""
