"""Material Point Method solver (000 Sec. 2.2): particle pool, grid, shape functions, MUSL step."""
from blastfsi.mpm.grid import FACE_KINDS, Grid, GridError, apply_boundaries
from blastfsi.mpm.musl import (Config, MPMError, Params, State, check_particles, energies, first_fault, initialize,
                               make_config, make_params, materialised_stencil, stable_dt, step)
from blastfsi.mpm.particles import (CapacityError, ParticleError, Particles, Totals, add_particles, add_particles_at,
                                    check_capacity,
                                    compact, concatenate, empty, insert, lattice, make_pool, model_output_fields,
                                    new_particles,
                                    remove_particles, sort_by_cell, surface_load, total_energy, total_mass,
                                    total_momentum, totals)
from blastfsi.mpm.shape import GIMP, LINEAR, SHAPES, Shape, stencil

__all__ = [
    "FACE_KINDS", "Grid", "GridError", "apply_boundaries",
    "Config", "MPMError", "Params", "State", "check_particles", "energies", "first_fault", "initialize",
    "make_config", "make_params", "materialised_stencil", "stable_dt", "step",
    "CapacityError", "ParticleError", "Particles", "Totals", "add_particles", "add_particles_at", "check_capacity",
    "compact",
    "concatenate", "empty", "insert", "lattice", "make_pool", "model_output_fields", "new_particles", "remove_particles", "sort_by_cell",
    "surface_load", "total_energy", "total_mass", "total_momentum", "totals",
    "GIMP", "LINEAR", "SHAPES", "Shape", "stencil",
]
