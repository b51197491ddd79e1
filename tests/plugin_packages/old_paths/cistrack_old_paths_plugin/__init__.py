"""A plugin package that imports cistrack the way docs/plugins.md showed in 0.1."""
