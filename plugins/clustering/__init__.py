"""Built-in clustering plugins."""
