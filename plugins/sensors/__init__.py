"""Built-in sensors plugins."""
