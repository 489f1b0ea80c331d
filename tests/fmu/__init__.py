"""The FMUs: the PythonFMU runtime (python/) and the native one (native/)."""
