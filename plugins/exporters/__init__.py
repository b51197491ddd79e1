"""Estimate file formats (CCSDS OEM, OPM)."""
