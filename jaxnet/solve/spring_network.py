"""The spring network of a scene: the metric of the Newton solver's damping.

Replace every twine and every cable bar by a zero-length spring of its traction stiffness EA / l0 (N/m):
the resulting stiffness matrix S is the elastic stiffness made isotropic. It is constant (independent of
the positions), symmetric positive semi-definite, zero only on rigid translations of unconnected parts,
and has the sparsity of the tangent.

Why this metric. Newton's tangent K of a net is singular at the usual start (a flat, stress-free net has no
out-of-plane stiffness, and the diamond mesh is a mechanism in its plane until the twines carry tension)
and, later, spans ten decades (EA/l0 against geometric stiffnesses T/l of lightly loaded twines).
Levenberg-Marquardt adds a multiple of a metric to K. The usual choice, a multiple of the identity, lets
every node move on its own: the step of a node held by nothing but damping is its load divided by the
damping, and the first steps crumple the net node by node. With ``K + mu S`` the damping acts between
neighbours instead, as a *prestress*: ``mu S`` is (for the transverse directions) the geometric stiffness
of a net whose every twine carries the tension ``mu EA`` — a fictitious prestrain ``mu`` (dimensionless).
A damped step is then the step of a prestressed net: smooth over the whole net, no crumpling, and as
``mu`` falls to zero near the solution the steps become pure Newton steps (quadratic convergence).
From a flat start this takes markedly fewer Newton iterations than an identity metric, which may not
converge at all.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.model import assemble


def _netting_springs(x, p, env):
    """Energy (J) of the zero-length springs of one triangle's twines: n (EA / l0) (|U|² + |V|²) / 2."""
    U, V, d = geometry.twine_vectors(x, p.uv)
    return geometry.twine_count(d) * 0.5 * p.ea_traction / p.l0 * (jnp.sum(U * U) + jnp.sum(V * V))


def _bar_spring(x, p, env):
    """Energy (J) of the zero-length spring of one bar: (EA / L0) |x1 - x0|² / 2."""
    s = x[1] - x[0]
    return 0.5 * p.ea_traction / p.rest_length * jnp.sum(s * s)


def _hexagonal_springs(x, p, env):
    """Hexagonal mesh: zero-length springs along the base-mesh vectors U and V, |d| of each, of the mean
    family stiffness mean(EA / l0) (a metric, not a model: it only has to be of the element's scale)."""
    U, V, d = geometry.twine_vectors(x, p.uv)
    k = jnp.mean(p.ea_traction / p.l0)
    return jnp.abs(d) * 0.5 * k * (jnp.sum(U * U) + jnp.sum(V * V))


SPRINGS = {"netting": _netting_springs, "bars": _bar_spring, "hexagonal": _hexagonal_springs}


def stiffness(scene, model, pattern):
    """CSR entries (nnz,) of the spring-network stiffness S (N/m) over the free coordinates."""
    x = jnp.asarray(scene.nodes.position)
    families = [f for f in assemble.stiff_families(model) if f in SPRINGS]
    return assemble.scatter_hessians(x, scene, pattern, {f: SPRINGS[f] for f in families})
