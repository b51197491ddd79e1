"""Built-in recorders plugins."""
