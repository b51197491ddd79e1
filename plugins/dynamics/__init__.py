"""Built-in dynamics plugins."""
