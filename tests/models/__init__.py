"""The element's effects: friction on the ground, the continuum, spectra, Masing, the connector."""
