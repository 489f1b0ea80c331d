"""The PythonFMU FMU: against the library, its loader, a hostile host, clean exits."""
