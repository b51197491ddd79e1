"""Built-in iod plugins."""
