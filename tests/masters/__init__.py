"""The FMUs in real co-simulation masters and what each host needs."""
