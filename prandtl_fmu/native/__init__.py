"""The native runtime: an FMU of a scene whose binary holds the library's compiled kernels and a C FMI layer, and
nothing of Python (issue 24). ``kernels.py`` compiles the kernels of a scene into C functions and object files,
``fmi2.c`` is the FMI 2.0 layer, ``build.py`` links and packs the FMU."""
