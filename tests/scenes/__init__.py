"""The scene format: its contract, its schema, the shipped scenes and the catalog of hard ones."""
