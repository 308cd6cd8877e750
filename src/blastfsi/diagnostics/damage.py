"""Damage of a structure on one of its faces, from its particles: the failed zone on the face toward a charge
and the tensile damage on the back face (000 Sec. 5.3: the crushing diameter of a slab under a charge, Fig. 14;
Sec. 5.5).

A face is the outer layer of a body normal to one axis, ``rows`` particle rows deep (by default a cell: the
particles per cell along the normal), taken in the reference (initial) configuration, so a crushed and displaced
surface is measured where it was. Each particle stands for its share of the face, ``volume0 / spacing`` (a ring
2 pi r dr on an r-z grid; per unit length in 2D plane strain). A particle counts as damaged when its damage
reaches the threshold. Two sizes of the damaged region:

* ``diameter`` (the crushing diameter): the face is cut into rings (strips in 2D plane strain) one ``ring_width``
  wide around the load's axis; walking out from the axis, every ring whose damaged share of area is at least
  ``fraction`` adds its width, and the first ring below it adds its damaged share of the width and ends the zone:
  the damaged zone connected to the axis (to the inner edge of an annulus, whose inner rings are skipped), to a
  fraction of a ring, whatever lies farther out (an edge's damage).
* ``equivalent_diameter``: the diameter of the disk of the whole damaged area of the face, edges included
  (the width of the strips in 2D plane strain).

Both are reported for several thresholds, so their sensitivity to it shows. Through the body's thickness,
``breach_diameter`` is the same connected measure on all its particles (volume shares): the zone around the
axis where at least ``fraction`` of the thickness has failed, where the structure breaks through.
"""
from __future__ import annotations

import numpy as np

THRESHOLDS = (0.5, 0.75, 1.0)


def sides_toward(load: float, normal_coordinate: np.ndarray) -> tuple[str, str] | None:
    """(the face toward a load at normal coordinate ``load``, the opposite face) of a body whose particles have
    these normal coordinates: ("upper", "lower") for a load above it, ("lower", "upper") below; None when the
    load lies within the body's extent."""
    if load > normal_coordinate.max():
        return "upper", "lower"
    if load < normal_coordinate.min():
        return "lower", "upper"
    return None


def face_layer(normal_coordinate: np.ndarray, side: str, depth: float) -> np.ndarray:
    """Mask of the particles within ``depth`` of the body's face ``side`` ("upper" | "lower") along the
    normal (reference coordinates)."""
    if side not in ("upper", "lower"):
        raise ValueError(f"side must be 'upper' or 'lower', got {side!r}")
    if not depth > 0.0:
        raise ValueError(f"depth must be > 0, got {depth}")
    face = normal_coordinate.max() if side == "upper" else normal_coordinate.min()
    return np.abs(normal_coordinate - face) < depth


def connected_radius(distance: np.ndarray, share: np.ndarray, damaged: np.ndarray, ring_width: float,
                     fraction: float = 0.5) -> float:
    """Radius of the damaged zone around the axis (module docstring): rings of ``ring_width`` from the axis."""
    if not ring_width > 0.0 or not 0.0 < fraction <= 1.0:
        raise ValueError(f"ring_width must be > 0 and fraction in (0, 1], got {ring_width}, {fraction}")
    ring = np.floor(distance / ring_width).astype(int)
    rings = ring.max(initial=-1) + 1
    total = np.bincount(ring, weights=share, minlength=rings)
    hit = np.bincount(ring, weights=np.where(damaged, share, 0.0), minlength=rings)
    present = total > 0.0  # (rings the body does not reach, inside an annulus, are skipped)
    shares = np.divide(hit, total, out=np.zeros(rings), where=present)
    below = np.flatnonzero(present & (shares < fraction))
    if below.size == 0:
        return float(rings * ring_width)
    k = below[0]
    if k == np.argmax(present):  # the body's innermost ring is not damaged: no zone
        return 0.0
    return float((k + shares[k]) * ring_width)


def damaged_face(reference: np.ndarray, volume0: np.ndarray, damage: np.ndarray, *, normal_axis: int, side: str,
                 spacing: float, rows: int, load_axis: np.ndarray, ring_width: float, mirror: float = 1.0,
                 planar: bool = False, thresholds=THRESHOLDS, fraction: float = 0.5) -> dict:
    """Sizes of the region of a body's face whose particles' ``damage`` reaches each threshold.

    reference: (n, d) reference positions of the body's particles; volume0: (n,) their initial volumes (r-z:
    ring volumes); spacing: the particle spacing along the normal; rows: the layer's particle rows; load_axis:
    (d,) a point of the load's axis (its normal coordinate is ignored); ring_width: of the rings of
    ``connected_radius`` (a cell); mirror: the factor of the symmetry planes through the axis (a quarter
    model: 4); planar: 2D plane strain (sizes are widths).
    """
    if rows < 1:
        raise ValueError(f"rows must be >= 1, got {rows}")
    layer = face_layer(reference[:, normal_axis], side, rows * spacing * (1.0 - 1e-9))
    distance = np.linalg.norm(np.delete(reference - load_axis, normal_axis, axis=1), axis=1)[layer]
    share = volume0[layer] / spacing
    out = {"face_area": float(mirror * share.sum() / rows), "ring_fraction": fraction, "by_threshold": []}
    for threshold in thresholds:
        hit = damage[layer] >= threshold
        area = mirror * share[hit].sum() / rows
        out["by_threshold"].append({
            "threshold": float(threshold), "area": float(area),
            "diameter": 2.0 * connected_radius(distance, share, hit, ring_width, fraction),
            "equivalent_diameter": float(area if planar else 2.0 * np.sqrt(area / np.pi))})
    return out


def breach_diameter(reference: np.ndarray, volume0: np.ndarray, damage: np.ndarray, *, normal_axis: int,
                    load_axis: np.ndarray, ring_width: float, threshold: float = 1.0, fraction: float = 0.5) -> float:
    """Diameter of the zone around the load's axis where at least ``fraction`` of the body's volume through its
    thickness has ``damage`` >= ``threshold`` (rings of ``ring_width``; module docstring)."""
    distance = np.linalg.norm(np.delete(reference - load_axis, normal_axis, axis=1), axis=1)
    return 2.0 * connected_radius(distance, volume0, damage >= threshold, ring_width, fraction)
