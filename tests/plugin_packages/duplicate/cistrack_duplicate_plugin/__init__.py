"""Registers a taken name on purpose."""
