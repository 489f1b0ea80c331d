"""The native runtime: an FMU of a scene whose binary holds the library's compiled kernels and a C FMI layer, and
nothing of Python (issue 24). ``kernels.py`` and ``network_kernels.py`` compile the kernels of a scene into C
functions and object files; ``fmi2.c`` and ``fmi3.c`` are the FMI 2.0 and 3.0 fronts (what they share: ``front.h``)
over the one state machine ``machine.h``, which runs the kind's calls, ``element.h``, ``connector.h`` or ``network.h``
(its variables and its calls into the kernels), over the services they call (``core.h``, ``state.h``, ``calls.h``)
and the kind's types (``element_types.h``, ``connector_types.h``, ``network_types.h``: ``kind.h`` chooses); a
header names nothing above it (the C layer: it marshals values, validates calls and calls kernels, the rule at the
top of each C file); ``build.py`` and ``network_build.py`` generate ``scene.h``, ``platforms.py`` links a binary per
platform, ``assemble.py`` packs the FMU."""
