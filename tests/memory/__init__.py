"""The effects with memory ([delay], [history], [dahl]): the library and the FMUs in both runtimes."""
