"""Exact and closed-form references, as validated callables."""
