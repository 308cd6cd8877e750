"""Accuracy study (not a timing): a point-energy blast crossing an MPM gas box, CFDMP against the
all-Eulerian run on the same grid, in r-z (2 kJ) or 2D Cartesian (40 kJ/m). docs/theory/cfdmp.md quotes it.

    python benchmarks/study_cfdmp_axisym_blast.py CELLS METHOD axi|cart [dotted.key=value ...]

Domain 120 x 120 mm, charge at the origin (axis / symmetry planes), MPM box r 40-80 mm x z 20-60 mm,
HLLC, 120 us. Prints per gauge (peak overpressure [Pa], positive impulse [Pa s], 1 %-of-peak arrival [s]).
"""
import sys
import time

import numpy as np

import blastfsi

GAUGES = [[0.06, 0.04], [0.09, 0.04], [0.03, 0.03], [0.0, 0.06], [0.05, 0.03]]  # 0 and 4 in the MPM box


def scenario(cells: int, method: str, axisymmetric: bool) -> dict:
    d = {"method": method, "name": "axisym-blast-study",
         "domain": {"geometry": "axisymmetric" if axisymmetric else "cartesian", "lower": [0.0, 0.0],
                    "upper": [0.12, 0.12]},
         "boundaries": {"x": ["axis" if axisymmetric else "symmetry", "outflow"], "y": ["symmetry", "outflow"]},
         "grid": {"cells": cells},
         "initial": {"kind": "point-energy", "energy": 2000.0 if axisymmetric else 4.0e4,
                     "ambient": {"material": "air", "density": 1.2, "pressure": 1.0e5}},
         "numerics": {"scheme": "hllc-muscl"}, "time": {"end": 1.2e-4},
         "output": {"history_samples": 601, "fields": 0, "plots": False, "gauges": GAUGES}}
    if method == "cfdmp":
        d["mpm_region"] = {"lower": [0.04, 0.02], "upper": [0.08, 0.06]}
    return d


def main(argv):
    cells, method, geometry = int(argv[0]), argv[1], argv[2]
    d = scenario(cells, method, geometry == "axi")
    d = blastfsi.scenario.apply_overrides(d, argv[3:])  # the CLI's --set syntax
    start = time.perf_counter()
    res = blastfsi.run(d)
    wall = time.perf_counter() - start
    t = np.asarray(res.history["time"])
    print(f"{method} {geometry} {cells} cells: {res.summary['steps']} steps, {wall:.1f} s")
    for k, pos in enumerate(GAUGES):
        p = np.asarray(res.history[f"gauge{k}_overpressure"])
        print(f"  gauge {k} {pos}: peak {p.max():.4g}  impulse {np.trapezoid(np.maximum(p, 0.0), t):.4g}  "
              f"arrival {t[np.argmax(p > 0.01 * p.max())]:.4g}")
    if method == "cfdmp":
        b = res.summary["budget"]
        print(f"  mass residual {b['max_mass_residual_relative']:.2g}, energy {b['energy_residual_relative']:.2g}")


if __name__ == "__main__":
    main(sys.argv[1:])
