"""Post-processing of solver states: fronts, errors against exact profiles."""
from blastfsi.diagnostics.profiles import front_position, l1_relative_error, zone_profile

__all__ = ["front_position", "l1_relative_error", "zone_profile"]
