"""The command line: the run's contract, hostile inputs, interrupted outputs, start-up, install."""
