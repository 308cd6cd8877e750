"""von Neumann-Richtmyer staggered Lagrangian solver for planar 1D gas flow
with a free-standing rigid plate (seed 002, Sec. 2). The driver reaches it
through its face in :mod:`blastfsi.lagrangian1d.method`."""
from blastfsi.lagrangian1d.scheme import (
    Afterburn,
    Boundaries,
    Gauges,
    Numerics,
    Params,
    State,
    Static,
    advance,
    initial_state,
    total_energy,
)

__all__ = ["Afterburn", "Boundaries", "Gauges", "Numerics", "Params", "State", "Static", "advance", "initial_state",
           "total_energy"]
