"""Named scenario builders: from a validated scenario to initial and boundary data."""
from blastfsi.problems.plate1d import Setup, build

__all__ = ["Setup", "build"]
