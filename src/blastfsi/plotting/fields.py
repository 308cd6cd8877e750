"""Pictures of a grid field: 1D line, 2D colour map, 3D colour map of a z-plane (default the middle)."""
from __future__ import annotations

import matplotlib
import numpy as np

from blastfsi.io.fields import grid_geometry
from blastfsi.plotting.common import plain, save
from blastfsi.plotting.units import scale, text

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def field_image(origin, spacing, field, z: float | None = None
                ) -> tuple[np.ndarray, tuple[float, float, float, float], float | None]:
    """(image, extent, z of the plane or None) of a cell-centred 2D field or of a 3D field's plane z.

    ``image[row, col]`` is the value at y-cell ``row``, x-cell ``col`` (row 0 at the lower y edge), as
    ``imshow(image, origin="lower", extent=extent)`` expects; extent = (x0, x1, y0, y1) of the cell faces.
    In 3D the plane is ``z`` (default the middle, z0 + nz dz / 2), the field interpolated linearly between
    the two cell layers whose centres bracket it (the middle layer for odd nz, the mean of the two around
    the middle for even nz); a plane closer to a face than the first layer's centre shows that layer, and
    the returned z is then that centre.
    """
    field = np.asarray(field)
    origin, spacing = grid_geometry(origin, spacing)
    if field.ndim != origin.size or origin.size not in (2, 3):
        raise ValueError(f"field must be a 2D or 3D cell array matching origin (ndim {origin.size}), "
                         f"got shape {field.shape}")
    z_plane = None
    if field.ndim == 3:
        nz = field.shape[2]
        z = origin[2] + 0.5 * nz * spacing[2] if z is None else z
        s = float(np.clip((z - origin[2]) / spacing[2] - 0.5, 0.0, nz - 1))  # in cell-centre index units
        k = min(int(np.floor(s)), max(nz - 2, 0))
        frac = s - k
        # (on a layer: that layer alone, so a NaN beyond it -- a structure's cells -- stays out, and nz = 1 works)
        field = field[:, :, k] if frac == 0.0 else (1.0 - frac) * field[:, :, k] + frac * field[:, :, k + 1]
        z_plane = float(origin[2] + (s + 0.5) * spacing[2])
    upper = origin[:2] + spacing[:2] * np.array(field.shape)
    return field.T, (float(origin[0]), float(upper[0]), float(origin[1]), float(upper[1])), z_plane


def _length_labels(names, values) -> tuple:
    """(scale of lengths, "name [unit]" of each axis name) for coordinates ``values``."""
    s = scale(values, "length")
    return s, tuple(s.label(n) for n in names)


def pressure_field_figure(origin, spacing, pressure, *, axis_labels=("x", "y", "z"), title: str = "pressure",
                          z_plane: float | None = None):
    """Figure of a cell-centred pressure field [Pa] on a uniform grid (lower corner ``origin``): 1D a line,
    2D a colour map, 3D the colour map of the plane ``z_plane`` (default the middle, :func:`field_image`).
    ``axis_labels`` name the axes (r, z in r-z); lengths and pressure are shown in units chosen from the data."""
    pressure = np.asarray(pressure, dtype=float)
    origin, spacing = grid_geometry(origin, spacing)
    if len(axis_labels) < origin.size:
        raise ValueError(f"axis_labels must name {origin.size} axes, got {list(axis_labels)}")
    ps = scale(pressure, "pressure")
    upper = origin + spacing * np.array(pressure.shape[:origin.size])
    ls, labels = _length_labels(axis_labels, np.concatenate([origin, upper]))
    if pressure.ndim == 1 and origin.size == 1:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        x = origin[0] + spacing[0] * (np.arange(pressure.size) + 0.5)
        ax.plot(x / ls.factor, pressure / ps.factor, lw=1.2)
        ax.set_xlabel(labels[0]), ax.set_ylabel(ps.label("pressure")), ax.grid(alpha=0.3)
        plain(ax.xaxis, ax.yaxis)
    else:
        image, extent, z_plane = field_image(origin, spacing, pressure, z_plane)
        fig, ax = plt.subplots(figsize=(8, 6))
        shown = ax.imshow(image / ps.factor, origin="lower", extent=tuple(e / ls.factor for e in extent),
                          aspect="equal", interpolation="nearest", cmap="viridis")
        bar = fig.colorbar(shown, ax=ax, label=ps.label("pressure"))
        ax.set_xlabel(labels[0]), ax.set_ylabel(labels[1])
        plain(ax.xaxis, ax.yaxis, bar.ax.yaxis)
        if z_plane is not None:
            title = f"{title}, plane {axis_labels[2]} = {text(z_plane, 'length')}"
    ax.set_title(title)
    fig.tight_layout()
    return fig


def plot_pressure_field(png_path, origin, spacing, pressure, *, axis_labels=("x", "y", "z"),
                        title: str = "pressure", z_plane: float | None = None) -> None:
    """:func:`pressure_field_figure` saved to ``png_path``."""
    save(pressure_field_figure(origin, spacing, pressure, axis_labels=axis_labels, title=title, z_plane=z_plane),
         png_path)


def particle_damage_figure(positions, damage, *, cell_size: float, axis_labels=("x", "y", "z"),
                           title: str = "damage", z_plane: float | None = None, profiles=None):
    """Figure of particles (P, ndim) coloured by damage (0 intact .. 1 failed). 1D: the damage profile
    against x, with the further ``profiles`` ({label: (P,) values 0..1}, e.g. tensile and compressive damage)
    beside it: a spall plane is where the tensile damage reaches 1. 3D: the particles within half a cell of
    the plane ``z_plane`` (default the middle of their z range)."""
    positions, damage = np.asarray(positions, dtype=float), np.asarray(damage, dtype=float)
    if positions.ndim != 2 or positions.shape[1] not in (1, 2, 3) or damage.shape != positions.shape[:1]:
        raise ValueError(f"positions must be (P, 1..3) and damage (P,), got {positions.shape} and {damage.shape}")
    ls, labels = _length_labels(axis_labels, positions[:, :2] if positions.size else [])
    fig, ax = plt.subplots(figsize=(8, 6 if positions.shape[1] > 1 else 4))
    if positions.shape[1] == 1:
        order = np.argsort(positions[:, 0])
        x = positions[order, 0] / ls.factor
        for n, (label, values) in enumerate({"damage": damage, **(profiles or {})}.items()):  # (points: particles
            ax.plot(x, np.asarray(values, float)[order], "o.x+"[n % 4], ms=3, ls="none",  # of a cell interleave)
                    label=label, zorder=3 - 0.1 * n, alpha=0.8)
        ax.set_xlabel(labels[0]), ax.set_ylabel("damage [-]"), ax.set_ylim(-0.05, 1.05), ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        plain(ax.xaxis)
    else:
        if positions.shape[1] == 3:
            z = positions[:, 2]
            if z_plane is None:
                z_plane = 0.5 * (z.min() + z.max()) if z.size else 0.0
            near = np.abs(z - z_plane) <= 0.5 * cell_size
            positions, damage = positions[near], damage[near]
            title = (f"{title}, |{axis_labels[2]} - {text(z_plane, 'length')}| <= "
                     f"{text(0.5 * cell_size, 'length', 3)}")
        shown = ax.scatter(positions[:, 0] / ls.factor, positions[:, 1] / ls.factor, c=damage, s=4,
                           cmap="inferno_r", vmin=0.0, vmax=1.0)
        fig.colorbar(shown, ax=ax, label="damage [-]")
        ax.set_aspect("equal")
        ax.locator_params(axis="x", nbins=3)  # (a thin plate's axis would crowd its tick labels)
        ax.tick_params(axis="x", labelrotation=45)
        ax.set_xlabel(labels[0]), ax.set_ylabel(labels[1])
        plain(ax.xaxis, ax.yaxis)
    fig.suptitle(title)  # (over the figure: a thin plate's axes are narrower than the title)
    fig.tight_layout()
    return fig


def plot_particle_damage(png_path, positions, damage, *, cell_size: float, axis_labels=("x", "y", "z"),
                         title: str = "damage", z_plane: float | None = None, profiles=None) -> None:
    """:func:`particle_damage_figure` saved to ``png_path``."""
    save(particle_damage_figure(positions, damage, cell_size=cell_size, axis_labels=axis_labels, title=title,
                                z_plane=z_plane, profiles=profiles), png_path)


def plot_face_damage(png_path, faces: list[tuple[str, np.ndarray, np.ndarray]], *, axisymmetric: bool,
                     title: str = "") -> None:
    """Save a PNG of damage on faces of a structure, side by side (000 Fig. 14): each face a (label, lateral
    positions (P, 1) r or (P, 2) x-y, values 0..1). r-z: the face revolved, ring means over 60 rings;
    3D: the particles in plan."""
    fig, axes = plt.subplots(1, len(faces), figsize=(4.2 * len(faces), 4.2), squeeze=False,
                             subplot_kw={"projection": "polar"} if axisymmetric else {})
    ls = scale(np.concatenate([np.ravel(lateral) for _, lateral, _ in faces]), "length")
    for ax, (label, lateral, values) in zip(axes[0], faces):
        lateral, values = np.asarray(lateral, float) / ls.factor, np.asarray(values, float)
        if axisymmetric:
            r = lateral[:, 0]
            edges = np.linspace(0.0, r.max(initial=1e-9), 61)
            ring = np.clip(np.digitize(r, edges) - 1, 0, len(edges) - 2)
            counts = np.bincount(ring, minlength=len(edges) - 1)
            mean = np.bincount(ring, values, len(edges) - 1) / np.maximum(counts, 1)
            theta = np.linspace(0.0, 2.0 * np.pi, 121)
            shown = ax.pcolormesh(theta, edges, np.tile(mean[:, None], (1, len(theta) - 1)), vmin=0.0, vmax=1.0,
                                  cmap="inferno_r")
            ax.set_xticks([])
            ax.tick_params(axis="y", labelsize=7)
            ax.set_title(f"{label}\n(radius in {ls.unit})", fontsize=9)
        else:
            shown = ax.scatter(lateral[:, 0], lateral[:, 1], c=values, s=4, cmap="inferno_r", vmin=0.0, vmax=1.0)
            ax.set_aspect("equal")
            ax.set_xlabel(ls.label("x")), ax.set_ylabel(ls.label("y"))
            plain(ax.xaxis, ax.yaxis)
            ax.set_title(label, fontsize=9)
    fig.colorbar(shown, ax=axes[0].tolist(), shrink=0.8, label="damage [-]")
    fig.suptitle(title, fontsize=10)
    save(fig, png_path)
