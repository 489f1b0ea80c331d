"""The native FMU: against the library, its instance layer, hostile hosts, platforms, bounds."""
