"""Built-in cistrack plugins. Each module is an ordinary plugin declared under the `cistrack` entry-point group."""
