"""The white noise: its Brownian path, its rules, the schemes, its FMUs in both runtimes."""
