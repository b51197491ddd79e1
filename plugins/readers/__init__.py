"""Observation file formats (readers and their matching writers)."""
