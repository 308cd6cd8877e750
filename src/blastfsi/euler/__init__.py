"""Eulerian finite-difference gas solver of CFDMP (000 Sec. 2.1): pure jittable kernels.

Schemes: 0 split Lax-Wendroff with adaptive viscosity (the paper's), 1 unsplit
HLLC-MUSCL, 2 split MUSCL-Hancock with HLLC fluxes; one or two materials
(five-equation products/air model, ERRATA 000-9); Cartesian 1D/2D/3D,
cylindrical (1D, 2D r-z) and spherical 1D.
"""
from blastfsi.euler.config import (AXIS, CARTESIAN, CYLINDRICAL, HLLC_HANCOCK, HLLC_MUSCL, LAX_WENDROFF, MC, MINMOD,
                                   OUTFLOW, PERIODIC, SPHERICAL, VAN_LEER, WALL, BlastTable, Config, Params,
                                   n_vars)
from blastfsi.euler.step import (advance_to, conservative, first_bad_cell, primitives, stable_dt, step,
                                 step_with_transfers, total, with_blast)

__all__ = ["Config", "Params", "n_vars", "advance_to", "conservative", "primitives", "stable_dt", "first_bad_cell",
           "step", "step_with_transfers", "total", "with_blast", "BlastTable",
           "CARTESIAN", "CYLINDRICAL", "SPHERICAL", "OUTFLOW", "WALL", "AXIS",
           "PERIODIC", "LAX_WENDROFF", "HLLC_MUSCL", "HLLC_HANCOCK", "VAN_LEER", "MINMOD", "MC"]
