"""Analyses on the library: identification, frequency domain, sweeps, Monte Carlo, Table 1, benchmarks."""
