"""Issue 6: conservative remap of a 1D spherical blast onto 1D spherical, r-z and 3D Cartesian grids."""
import numpy as np
import pytest

from blastfsi.detonation import remap as rm
from blastfsi.eos.jwl import JWLParams, ideal_gas_params

TNT = JWLParams(3.712e11, 3.21e9, 4.15, 0.95, 0.3, 1630.0)  # seed 000 Sec. 4.1
AIR = ideal_gas_params(1.4)
RHO0, P0 = 1.225, 101356.0


def blast_profile(n=300, r_shock=0.3, r_fire=0.12):
    """A blast-like 1D profile: hot products inside r_fire, shocked air to r_shock, ambient beyond."""
    edges = np.r_[np.linspace(0.0, r_fire, 101)[:-1], np.geomspace(r_fire, 0.6, n - 99)]
    vol = 4 / 3 * np.pi * np.diff(edges**3)
    rc = 0.5 * (edges[1:] + edges[:-1])
    prod = rc < r_fire
    behind = (rc >= r_fire) & (rc < r_shock)
    rho = np.where(prod, 2.0 + rc, np.where(behind, RHO0 * (1 + 3 * (rc / r_shock) ** 4), RHO0))
    u = np.where(rc < r_shock, 400.0 * rc / r_shock, 0.0)
    p = np.where(prod, 4e5, np.where(behind, P0 * (1 + 8 * (rc / r_shock) ** 3), P0))
    eos_e = np.where(prod, 1.0 / 0.3, 1.0 / 0.4) * p  # rho e of (nearly ideal) products and air
    m = rho * vol
    return rm.Profile1D(edges, m, np.where(prod, m, 0.0), m * u, eos_e * vol + 0.5 * m * u**2)


def totals(out):
    return np.sum(out.mass), np.sum(out.products), np.sum(out.energy)


def expected(profile, r_max, v_domain, share):
    inside = profile.edges[1:] <= r_max + 1e-12
    ball = share * 4 / 3 * np.pi * r_max**3
    return (share * np.sum(profile.mass[inside]) + RHO0 * (v_domain - ball), share * np.sum(profile.products),
            share * np.sum(profile.energy[inside]) + P0 / 0.4 * (v_domain - ball))


GRIDS = {
    "spherical": ((np.linspace(0.0, 0.5, 101),), [0.0], ((True, False),), 1.0),
    "axisymmetric": ((np.linspace(0.0, 0.4, 81), np.linspace(-0.4, 0.4, 161)), [0.0, 0.05],
                     ((True, False), (False, False)), 1.0),
    "axisymmetric-ground": ((np.linspace(0.0, 0.4, 81), np.linspace(0.0, 0.4, 81)), [0.0, 0.0],
                            ((True, False), (True, False)), 0.5),
    "cartesian": ((np.linspace(-0.35, 0.35, 36), np.linspace(-0.4, 0.3, 36), np.linspace(-0.35, 0.35, 36)),
                  [0.01, -0.05, 0.0], ((False,) * 2,) * 3, 1.0),
}


@pytest.mark.parametrize("name", list(GRIDS))
def test_remap_conserves_mass_products_energy_to_round_off(name):
    edges, centre, mirrors, share = GRIDS[name]
    geometry = name.split("-")[0]
    prof = blast_profile()
    r_max = rm.disturbed_radius(prof, RHO0, P0 / 0.4)
    assert r_max == pytest.approx(0.3, abs=0.01)
    out = rm.remap(prof, edges, geometry, centre, mirrors, RHO0, P0, TNT, AIR, n_sub=4)
    assert out.share == share
    want = expected(prof, r_max, float(np.sum(out.volume)), share)
    for got, ref in zip(totals(out), want):
        assert got == pytest.approx(ref, rel=1e-11)  # round-off of summing ~10^5 sub-cells
    # the radial momentum of every sub-cell points away from the centre: in 1D spherical it is the
    # 1D momentum itself; a full ball off the grid's centre still has a zero vector sum only up to
    # the sampling of the sphere, a vanishing fraction of sum |rho u| here
    if geometry == "spherical":
        inside = prof.edges[1:] <= r_max + 1e-12
        assert np.sum(out.momentum[0]) == pytest.approx(np.sum(prof.momentum[inside]), rel=1e-13)
    if geometry == "cartesian":
        scale = np.sum(np.sqrt(np.sum(out.momentum**2, axis=0)))
        assert np.all(np.abs(np.sum(out.momentum, axis=(1, 2, 3))) < 0.02 * scale)


def test_remapped_cells_reproduce_the_profile_and_the_shock_radius():
    # 1D spherical grid: cells are shells, so every cell value is a mass/volume-weighted mean of
    # the zones it overlaps; the shock (last disturbed zone, r = 0.3) lies in the cell holding it
    edges, centre, mirrors, _ = GRIDS["spherical"]
    prof = blast_profile()
    out = rm.remap(prof, edges, "spherical", centre, mirrors, RHO0, P0, TNT, AIR, n_sub=8)
    dx = edges[0][1] - edges[0][0]
    rc = 0.5 * (edges[0][1:] + edges[0][:-1])
    disturbed = rc[np.abs(out.pressure / P0 - 1) > 1e-3]  # the ball's edge cells carry its sampling error
    assert abs(disturbed.max() - 0.3) <= dx
    np.testing.assert_allclose(out.pressure[rc > 0.3 + dx], P0, rtol=1e-12)
    # pressure of pure-air cells behind the shock from the mixture EOS equals the profile's
    sel = (rc > 0.15) & (rc < 0.28)
    np.testing.assert_allclose(out.pressure[sel], P0 * (1 + 8 * (rc[sel] / 0.3) ** 3), rtol=0.05)
    assert np.all(out.alpha[rc < 0.11] == 1.0) and np.all(out.alpha[rc > 0.13] == 0.0)


def test_ball_crossing_an_open_face_is_refused():
    prof = blast_profile()
    edges = (np.linspace(-0.25, 0.25, 26),) * 3
    with pytest.raises(rm.RemapError, match="crosses the lower x face"):
        rm.remap(prof, edges, "cartesian", [0.0, 0.0, 0.0], ((False,) * 2,) * 3, RHO0, P0, TNT, AIR)
    with pytest.raises(rm.RemapError, match="axis"):
        rm.remap(prof, GRIDS["axisymmetric"][0], "axisymmetric", [0.1, 0.0], ((True, False),) * 2, RHO0, P0, TNT,
                 AIR)
