"""A tiny third-party plugin distribution for cistrack's registry tests."""
