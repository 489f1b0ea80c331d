"""The native runtime: an FMU of a scene whose binary holds the library's compiled kernels and a C FMI layer, and
nothing of Python (issue 24). ``kernels.py`` and ``network_kernels.py`` compile the kernels of a scene into C
functions and object files; ``fmi2.c`` and ``fmi3.c`` are the FMI 2.0 and 3.0 fronts (what they share: ``front.h``)
over the one instance layer ``core.h`` (with ``state.h``, ``calls.h``), which each kind, ``element.h``,
``connector.h`` or ``network.h``, serves with its variables and its calls into the kernels (the C layer: it marshals
values, validates calls and calls kernels, the rule at the top of each C file); ``build.py`` and
``network_build.py`` generate ``scene.h``, ``platforms.py`` links a binary per platform, ``assemble.py`` packs the
FMU."""
