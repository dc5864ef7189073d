"""See the package docstring: nothing here is called."""
