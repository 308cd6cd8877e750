"""Shipped example scenarios (TOML files in this package)."""
