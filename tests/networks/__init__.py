"""Networks of nodes: their mechanics, the massless chain, their FMUs in both runtimes."""
