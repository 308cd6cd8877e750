"""Tensor helpers shared by the constitutive models (pure JAX, leading axis n).

Stress is stored in Voigt order ``[xx, yy, zz, yz, xz, xy]`` (tensor components,
tension positive); strain and spin increments arrive as full (n, 3, 3) tensors.

* Objective rotation: 000 Eq. (30) adds ``dW sigma - sigma dW`` (dW the spin
  increment of Eq. 28), which is the Jaumann rate to first order but does not
  keep the invariants of sigma exactly. We rotate with the Hughes-Winget
  (1980) Cayley transform ``R = (I - dW/2)^-1 (I + dW/2)``, ``sigma <- R sigma R^T``:
  it equals Eq. (30) to first order in dW and is exactly orthogonal, so a pure
  spin leaves the invariants unchanged to round-off (T.J.R. Hughes, J. Winget,
  IJNME 15 (1980) 1862-1867).
* Energy: 000 Eq. (13), E-dot = J sigma:eps-dot with E per unit initial volume,
  i.e. de = sigma:d eps / rho per unit mass. Integrated with the midpoint
  (trapezoidal) stress and the specific volume change ``dv = tr(d eps)/rho_old``
  that Eq. (29) implies (rho_new = rho_old / (1 + tr d eps)), so the p dV work
  is exactly -p_mid (v_new - v_old).
"""
from __future__ import annotations

import jax.numpy as jnp

# Voigt index pairs [xx, yy, zz, yz, xz, xy]
_I = (0, 1, 2, 1, 0, 0)
_J = (0, 1, 2, 2, 2, 1)
IDENTITY_VOIGT = jnp.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])


def to_voigt(t):
    """Symmetric (n, 3, 3) tensor -> (n, 6) Voigt (symmetrised)."""
    ts = 0.5 * (t + jnp.swapaxes(t, -1, -2))
    return jnp.stack([ts[..., i, j] for i, j in zip(_I, _J)], axis=-1)


def from_voigt(v):
    """(n, 6) Voigt -> symmetric (n, 3, 3) tensor."""
    xx, yy, zz, yz, xz, xy = (v[..., k] for k in range(6))
    return jnp.stack([jnp.stack([xx, xy, xz], -1),
                      jnp.stack([xy, yy, yz], -1),
                      jnp.stack([xz, yz, zz], -1)], -2)


def contract(a_voigt, b_voigt):
    """a:b for two symmetric tensors in Voigt form (written out: XLA:CPU's reduction over a short
    trailing axis is several times slower than the elementwise adds)."""
    a, b = a_voigt, b_voigt
    return (a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]
            + 2.0 * (a[..., 3] * b[..., 3] + a[..., 4] * b[..., 4] + a[..., 5] * b[..., 5]))


def trace(v):
    return v[..., 0] + v[..., 1] + v[..., 2]


def pressure(stress):
    """p = -tr(sigma)/3 (compression positive)."""
    return -trace(stress) / 3.0


def deviator(v):
    """Deviatoric part of a Voigt tensor."""
    return v - (trace(v) / 3.0)[..., None] * IDENTITY_VOIGT


def von_mises(s):
    """Equivalent stress sqrt(3/2 s:s) of a deviator s (Voigt)."""
    return jnp.sqrt(1.5 * contract(s, s))


def compose(s, p):
    """Stress from deviator s and pressure p: sigma = s - p I."""
    return s - p[..., None] * IDENTITY_VOIGT


def rotate(stress, dspin):
    """Objective (Jaumann) rotation of 000 Eq. (30) by the Hughes-Winget Cayley transform.

    For a skew A = dW/2 with axial vector a: R = (I - A)^-1 (I + A) = I + 2 (A + A A) / (1 + |a|^2),
    sigma <- R sigma R^T. Written out component-wise (elementwise ops fuse into one loop).
    """
    a1, a2, a3 = 0.5 * dspin[..., 2, 1], 0.5 * dspin[..., 0, 2], 0.5 * dspin[..., 1, 0]
    c = 2.0 / (1.0 + a1 * a1 + a2 * a2 + a3 * a3)
    # A = [[0, -a3, a2], [a3, 0, -a1], [-a2, a1, 0]], (A A)_ij = a_i a_j - |a|^2 delta_ij
    r = [[1.0 + c * (a1 * a1 - (a1 * a1 + a2 * a2 + a3 * a3)), c * (-a3 + a1 * a2), c * (a2 + a1 * a3)],
         [c * (a3 + a2 * a1), 1.0 + c * (a2 * a2 - (a1 * a1 + a2 * a2 + a3 * a3)), c * (-a1 + a2 * a3)],
         [c * (-a2 + a3 * a1), c * (a1 + a3 * a2), 1.0 + c * (a3 * a3 - (a1 * a1 + a2 * a2 + a3 * a3))]]
    xx, yy, zz, yz, xz, xy = (stress[..., k] for k in range(6))
    sig = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]
    m = [[sum(r[i][k] * sig[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    out = [sum(m[i][k] * r[j][k] for k in range(3)) for i, j in zip(_I, _J)]
    return jnp.stack(out, axis=-1)


def old_density(rho_new, dstrain_voigt):
    """rho at the start of the step from 000 Eq. (29): rho_old = rho_new (1 + tr d eps)."""
    return rho_new * (1.0 + trace(dstrain_voigt))


def energy_trapezoidal(e_old, stress_old, stress_new, dstrain_voigt, rho_old):
    """000 Eq. (13) with the midpoint stress: e_new = e_old + (sigma_old + sigma_new)/2 : d eps / rho_old."""
    return e_old + 0.5 * contract(stress_old + stress_new, dstrain_voigt) / rho_old


def energy_implicit(e_old, s_old, s_new, p_old, f_new, g_new, dstrain_voigt, rho_old):
    """000 Eq. (13) for an EOS of Mie-Grueneisen form p = f(rho) + g(rho) e (implicit in e).

    e_new = e_old + [(s_old + s_new)/2 : d eps - (p_old + p_new)/2 tr(d eps)] / rho_old with
    p_new = f_new + g_new e_new, solved for e_new (the form of 002 Eq. 16). Returns (e_new, p_new).
    """
    dv = trace(dstrain_voigt) / rho_old
    w_dev = 0.5 * contract(s_old + s_new, dstrain_voigt) / rho_old
    e_new = (e_old + w_dev - 0.5 * (p_old + f_new) * dv) / (1.0 + 0.5 * g_new * dv)
    return e_new, f_new + g_new * e_new


def radial_return(s_trial, sigma_eq_trial, sigma_target):
    """Scale the trial deviator onto the von Mises circle of radius ``sigma_target`` where it lies outside."""
    scale = jnp.where(sigma_eq_trial > sigma_target,
                      sigma_target / jnp.where(sigma_eq_trial > 0.0, sigma_eq_trial, 1.0), 1.0)
    return s_trial * scale[..., None]


def equivalent_strain(dstrain_voigt):
    """Von Mises equivalent strain increment sqrt(2/3 dev(d eps):dev(d eps))."""
    d = deviator(dstrain_voigt)
    return jnp.sqrt(2.0 / 3.0 * contract(d, d))
