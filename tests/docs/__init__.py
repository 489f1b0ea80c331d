"""The documentation stays true and the layout shows the architecture."""
