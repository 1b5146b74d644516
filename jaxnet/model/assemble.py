"""Global assembly: total energy, out-of-balance force and sparse tangent stiffness of a scene.

Per element family (netting triangles, cable bars, bending hinges, nodes), the active terms are summed
into one element function, evaluated on the gathered vertex positions and vmapped over the elements:
*energy* terms into an element energy (J), *force* terms (drag, catch pressure: not conservative) into
element nodal forces (N). The out-of-balance force is

    F = loads - grad(energy) + forces,

and the tangent K = -dF/dx is, per element, the Hessian of the element energy (``jax.jacfwd`` over
``jax.grad``) minus the Jacobian of the element forces (``jax.jacfwd``), vmapped, scattered by
``segment_sum`` into the entries of a CSR matrix over the free coordinates. With force terms, K is not
symmetric. The CSR structure and the slot of every element-matrix entry are computed once per scene in
numpy (:func:`build_pattern`) and passed to the jitted functions as arguments — never closed over, so XLA
does not constant-fold large index arrays. No dense global matrix is ever formed.

The same tangent can instead be assembled from the hand-derived element matrices of
:mod:`jaxnet.closed_form` (``tangent(..., stiffness="closed_form")``): for each term that has one, its
closed form replaces its autodiff matrix; the two paths never share a term's computation.

Some force terms depend on a global quantity of the whole net (the catch front, placed so that the
enclosed volume is the catch volume): each such term's ``state(x, scene)`` is computed once per
evaluation and handed to its elements; the tangent treats it as constant (a quasi-Newton
approximation of that one coupling, stated where it is used).

In a time step (:mod:`jaxnet.solve.dynamics`) the drag terms depend on the vertices' velocities too,
(x - x_previous)/Δt by the book's backward difference (4.266): ``forces`` and ``tangent`` then take a
:class:`Motion`, and the velocity is formed inside the differentiated element function, so the tangent
holds the drag's damping (1/Δt) dF/dv as well as its dependence on the positions.

In a time step in waves the free surface is the wave's, not the mean level: the environment then holds the
elevation over each node (``Environment.surface_elevation``) and each element is evaluated in its own
environment, whose ``surface_level`` is the surface's height over each of its vertices
(:func:`element_environment`), so buoyancy and the wetted share of the drags take the local surface.

Sign convention: ``force`` is the out-of-balance force on the nodes (N), zero at equilibrium;
``tangent`` is K = -d force / dx (book eq. 4.46).
"""

from __future__ import annotations

import hashlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet.memo import Memo
from jaxnet.model import STIFFNESS_PATHS, ActiveTerm
from jaxnet.terms.term import resolve

class Motion(eqx.Module):
    """The past of an implicit time step, for velocity-dependent forces: the positions x_previous (N, 3) in
    m at the last time and the step Δt (s) to the new one; a vertex's velocity is (x - x_previous)/Δt."""

    x_previous: jax.Array
    time_step: jax.Array


def connectivity(scene, family):
    """(E, k) node indices of the elements of a family ("nodes": each node is its own element)."""
    if family == "nodes":
        return jnp.arange(scene.n_nodes)[:, None]
    f = getattr(scene, family)
    return f.ends if family == "bars" else f.vertices


class Pattern(eqx.Module):
    """Sparse structure of the tangent over the free coordinates (arrays; built once per scene).

    free: (n,) flat indices (3 * node + axis) of the free coordinates.
    slots: per family with stiffness, (E, (3k)²) position of each element-matrix entry in the CSR data,
      ``nnz`` for entries that touch a fixed coordinate (dropped).
    diagonal: (n,) position of the diagonal entries in the CSR data.
    indptr, indices, rows: CSR structure and the row of each entry (for products).
    """

    free: jax.Array
    slots: dict
    diagonal: jax.Array
    indptr: jax.Array
    indices: jax.Array
    rows: jax.Array

    @property
    def n(self):
        return self.free.shape[0]

    @property
    def nnz(self):
        return self.indices.shape[0]


def stiff_families(model):
    """Families with a stiffness: those with an energy or a force term."""
    return tuple(sorted({t.term.family for t in model if t.term.kind in ("energy", "force")}))


def _families(model, kind):
    return tuple(sorted({t.term.family for t in model if t.term.kind == kind}))


#: patterns built so far, by a digest of what decides them (:func:`build_pattern`)
_PATTERNS = Memo(maxsize=16)


def build_pattern(scene, model) -> Pattern:
    """CSR structure of the tangent and element slot maps, in numpy, once per scene.

    It depends on the fixed coordinates and the connectivity of the families with a stiffness only, and is
    kept for them (by a digest of those arrays): a second solve of the same net (another load, another
    start, a warm solve) takes it back instead of building it again."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool).ravel()
    families = stiff_families(model)
    digest = hashlib.blake2b(fixed.tobytes() + repr((scene.n_nodes, families)).encode(), digest_size=16)
    for family in families:
        if family != "nodes":
            digest.update(np.ascontiguousarray(connectivity(scene, family), dtype=np.int64).tobytes())
    return _PATTERNS.get_or_make(digest.digest(), lambda: pattern_of(scene, families, fixed))


def pattern_of(scene, families, fixed) -> Pattern:
    """The pattern of :func:`build_pattern` for the ``families`` with a stiffness and the flat ``fixed`` mask,
    built anew."""
    free = np.flatnonzero(~fixed)
    n = free.size
    dof_map = np.full(fixed.size, -1, dtype=np.int64)
    dof_map[free] = np.arange(n)
    keys_per_family = {}
    all_keys = [np.arange(n, dtype=np.int64) * (n + 1)]  # the diagonal is always present
    for family in families:
        conn = np.arange(scene.n_nodes)[:, None] if family == "nodes" else np.asarray(connectivity(scene, family))
        conn = conn.astype(np.int64)
        dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(conn.shape[0], -1)
        fd = dof_map[dofs]
        r = np.broadcast_to(fd[:, :, None], fd.shape + fd.shape[-1:])
        c = np.broadcast_to(fd[:, None, :], fd.shape + fd.shape[-1:])
        keys = np.where((r >= 0) & (c >= 0), r * n + c, -1).reshape(conn.shape[0], -1)
        keys_per_family[family] = keys
        all_keys.append(keys[keys >= 0])
    unique = np.unique(np.concatenate(all_keys))
    nnz = unique.size
    rows = unique // n
    indices = (unique % n).astype(np.int32 if nnz < 2**31 else np.int64)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    slots = {}
    for family, keys in keys_per_family.items():
        s = np.searchsorted(unique, keys)
        slots[family] = np.where(keys >= 0, s, nnz).astype(np.int64)
    diagonal = np.searchsorted(unique, np.arange(n, dtype=np.int64) * (n + 1))
    # device_put, not jnp.asarray: jax 0.10 stages a numpy array through a program compiled per shape
    return Pattern(
        free=jax.device_put(free),
        slots={k: jax.device_put(v) for k, v in slots.items()},
        diagonal=jax.device_put(diagonal),
        indptr=jax.device_put(indptr),
        indices=jax.device_put(indices),
        rows=jax.device_put(rows),
    )


def positions(x_free, scene, pattern):
    """(N, 3) positions: the free coordinates from ``x_free``, the fixed ones from the scene."""
    x0 = jnp.asarray(scene.nodes.position).ravel()
    return x0.at[pattern.free].set(x_free).reshape(-1, 3)


def _family_energy(model, family, elastic_scale=1.0):
    terms = [t for t in model if t.term.family == family and t.term.kind == "energy"]

    def energy(x, p, env):
        total = 0.0
        for t in terms:
            with jax.named_scope(t.name):
                e = t.energy(x, p, env)
            total = total + (elastic_scale * e if t.term.elastic else e)
        return total

    return energy


def _family_force(model, family):
    terms = [t for t in model if t.term.family == family and t.term.kind == "force"]

    def force(x, p, env, state, velocity=None):
        total = jnp.zeros_like(x)
        for t in terms:
            # the vertices' velocities (m/s) go to the terms that feel them, in dynamics
            with jax.named_scope(t.name):
                total = total + t.force(x, p, env, state.get(t.name), velocity)
        return total

    return force


def _velocity(x, x_previous, motion):
    """Vertex velocities (k, 3) in m/s by the backward difference (4.266, sign corrected), None in statics."""
    return None if motion is None else (x - x_previous) / motion.time_step


def surface_levels(scene, family, conn):
    """The height (m) of the free surface over each vertex of each element of a family: (E, k), (E,) for the
    nodes (a node is its own element); a placeholder (E, 0) where the environment has no elevation over its
    nodes (``Environment.surface_elevation`` None: the mean level ``surface_level``, the same for all)."""
    env = scene.environment
    if env.surface_elevation is None:
        return jnp.zeros((conn.shape[0], 0))
    level = env.surface_level + jnp.asarray(env.surface_elevation)[conn]
    return level[:, 0] if family == "nodes" else level


def element_environment(env, level):
    """The environment one element sees: ``env`` with its free surface at ``level`` over the element's vertices
    (a row of :func:`surface_levels`), where the environment has an elevation over its nodes (a time step in
    waves); ``env`` itself otherwise. The terms read the surface's height as ``env.surface_level`` either way, a
    scalar or one height per vertex, which their formulas take element-wise."""
    if env.surface_elevation is None:
        return env
    return eqx.tree_at(lambda e: e.surface_level, env, level)


def _previous(scene, conn, motion):
    """The elements' vertex positions at the last time (E, k, 3), or a placeholder in statics."""
    return jnp.zeros((conn.shape[0], 0)) if motion is None else motion.x_previous[conn]


def states(x, scene, model, previous=None):
    """Global quantities some force terms need (e.g. the catch front), computed once from positions x: terms
    that share a state function (the catch pressure and the netting drag behind the front) share its value.
    ``previous``: the states at nearby positions (a dict as returned here: the solver's last iterate), from
    which their solutions start; None to start from scratch. The answer is the same, to each solution's
    tolerance."""
    by_function, out = {}, {}
    for t in model:
        if t.term.kind == "force" and t.term.state is not None:
            function = resolve(t.term.state)
            if function not in by_function:
                start = None if previous is None else previous.get(t.name)
                by_function[function] = function(x, scene, start)
            out[t.name] = by_function[function]
    return out


def energy(x, scene, model: tuple[ActiveTerm, ...], elastic_scale=1.0):
    """Total stored energy (J) of all energy terms at positions x (N, 3); the elastic terms' (twines,
    bars, mesh opening, knots, bending: :attr:`jaxnet.terms.term.Term.elastic`) multiplied by ``elastic_scale``
    (1 for the net as it is; the static solver's stiffness continuation solves softer nets first)."""
    total = 0.0
    for family in _families(model, "energy"):
        conn = connectivity(scene, family)
        fam = getattr(scene, family)
        energy_of = _family_energy(model, family, elastic_scale)
        env = scene.environment

        def element(xe, p, level, energy_of=energy_of):
            return energy_of(xe, p, element_environment(env, level))

        e = jax.vmap(element)(x[conn], fam, surface_levels(scene, family, conn))
        total = total + jnp.sum(e)
    return total


def loads(scene, model):
    """(N, 3) constant nodal loads (N) of all load terms: weight, buoyancy, external forces."""
    n = scene.n_nodes
    f = jnp.zeros((n, 3))
    for t in model:
        if t.term.kind != "load":
            continue
        with jax.named_scope(t.name):
            family = t.term.family
            fam = scene.nodes if family == "nodes" else getattr(scene, family)
            per_elem = jax.vmap(lambda p: t.load(p, scene.environment))(fam)
            conn = jnp.arange(n)[:, None] if family == "nodes" else connectivity(scene, family)
            f = f.at[conn.ravel()].add(per_elem.reshape(-1, 3))
    return f


def potential(x, scene, model, load):
    """Total potential energy (J): stored energy minus the work of the constant loads."""
    return energy(x, scene, model) - jnp.sum(load * x)


def forces(x, scene, model, state=None, motion: Motion | None = None):
    """(N, 3) nodal forces (N) of the force terms (drag, pressure: not conservative) at positions x;
    ``motion``: in a time step, the past that gives the vertices' velocities (drag on relative velocity)."""
    state = states(x, scene, model) if state is None else state
    total = jnp.zeros_like(x)
    for family in _families(model, "force"):
        conn = connectivity(scene, family)
        fam = getattr(scene, family)
        force = _family_force(model, family)

        def element(xe, p, xp, level, force=force):
            return force(xe, p, element_environment(scene.environment, level), state, _velocity(xe, xp, motion))

        f = jax.vmap(element)(x[conn], fam, _previous(scene, conn, motion), surface_levels(scene, family, conn))
        total = total.at[conn.ravel()].add(f.reshape(-1, 3))
    return total


def nodal_force(x, scene, model, load):
    """(N, 3) out-of-balance force on every node (N), including reactions' share at fixed coordinates."""
    f = load - jax.grad(energy)(x, scene, model)
    if _families(model, "force"):
        f = f + forces(x, scene, model)
    return f


def term_forces(x, scene, model):
    """Per term, the (N, 3) nodal forces (N) it exerts at positions x: the force breakdown of a result.

    Energy terms give -grad of their own energy, load terms their load, force terms their force.
    """
    state = states(x, scene, model)
    out = {}
    for t in model:
        only = (t,)
        if t.term.kind == "energy":
            out[t.name] = -jax.grad(energy)(x, scene, only)
        elif t.term.kind == "load":
            out[t.name] = loads(scene, only)
        else:
            out[t.name] = forces(x, scene, only, {t.name: state.get(t.name)})
    return out


def forces_by_element(x, scene, model):
    """Per term, the (E, k, 3) force (N) each element of its family exerts on each of its k vertices at positions
    x (N, 3), before the elements' forces are summed onto the nodes (:func:`term_forces` is their sum): what
    tells a force by what carries it (the weight of each cable, of the sinkers and of the floats; a node is its
    own element, k = 1).

    Energy terms give -grad of the element's own energy, load terms their load, force terms their force, each
    on the element's environment (:func:`element_environment`) and, for a force term, its global state."""
    state = states(x, scene, model)
    env = scene.environment
    out = {}
    for t in model:
        family = t.term.family
        conn = connectivity(scene, family)
        rows = getattr(scene, family)
        levels = surface_levels(scene, family, conn)
        with jax.named_scope(t.name):
            if t.term.kind == "energy":
                def element(xe, p, level, t=t):
                    return -jax.grad(t.energy)(xe, p, element_environment(env, level))
                out[t.name] = jax.vmap(element)(x[conn], rows, levels)
            elif t.term.kind == "load":
                out[t.name] = jax.vmap(lambda p, t=t: t.load(p, env))(rows).reshape(conn.shape[0], -1, 3)
            else:
                def element(xe, p, level, t=t):
                    return t.force(xe, p, element_environment(env, level), state.get(t.name))
                out[t.name] = jax.vmap(element)(x[conn], rows, levels)
    return out


def scatter_hessians(x, scene, pattern, element_energies, element_forces=None, state=None, element_blocks=None,
                     motion: Motion | None = None):
    """CSR entries (nnz,) of the stiffness of per-element energies and forces: :func:`element_stiffnesses`
    summed into the pattern's slots (:func:`scatter_stiffnesses`); same arguments."""
    return scatter_stiffnesses(element_stiffnesses(x, scene, element_energies, element_forces, state, element_blocks,
                                                   motion), pattern)


def scatter_stiffnesses(blocks, pattern):
    """CSR entries (nnz,) of the element matrices ``blocks`` ({family: (E, 3k, 3k)}, N/m) summed into the
    pattern's slots (entries on fixed coordinates are dropped)."""
    data = jnp.zeros(pattern.nnz + 1)
    for family, block in blocks.items():
        data = data + jax.ops.segment_sum(block.reshape(-1), pattern.slots[family].reshape(-1), pattern.nnz + 1)
    return data[:-1]


def element_stiffnesses(x, scene, element_energies, element_forces=None, state=None, element_blocks=None,
                        motion: Motion | None = None):
    """{family: (E, 3k, 3k)} element stiffness matrices (N/m) of per-element energies and forces.

    ``element_energies[family](x, p, env)`` (J) is differentiated twice (``jax.jacfwd`` of ``jax.grad``)
    on its own vertices; ``element_forces[family](x, p, env, state)`` (N) once (``jax.jacfwd``), with
    the sign of K = -dF/dx; ``element_blocks[family](x, p, env, state)`` gives (3k, 3k) element matrices
    directly (the closed-form path); all vmapped over the family, the terms of a family summed element by
    element. ``motion``: in a time step, the forces' vertex velocities (x - x_previous)/Δt are formed
    inside the differentiated function.
    """
    out = {}
    element_forces = element_forces or {}
    element_blocks = element_blocks or {}
    for family in sorted(set(element_energies) | set(element_forces) | set(element_blocks)):
        conn = connectivity(scene, family)
        fam = getattr(scene, family)
        k = conn.shape[1]
        energy_fn, force_fn, block_fn = element_energies.get(family), element_forces.get(family), element_blocks.get(family)

        def stiffness(xe, p, xp, level, energy_fn=energy_fn, force_fn=force_fn, block_fn=block_fn, k=k):
            env = element_environment(scene.environment, level)
            block = jnp.zeros((3 * k, 3 * k))
            if energy_fn is not None:
                flat = lambda v: energy_fn(v.reshape(k, 3), p, env)  # noqa: E731
                block = block + jax.jacfwd(jax.grad(flat))(xe.ravel())
            if force_fn is not None:
                def flat(v):
                    v = v.reshape(k, 3)
                    return force_fn(v, p, env, state, _velocity(v, xp, motion)).ravel()

                block = block - jax.jacfwd(flat)(xe.ravel())
            if block_fn is not None:
                # in a time step the moving drags' closed forms take the vertices' velocities and Δt
                moving = {} if motion is None else {"velocity": _velocity(xe, xp, motion), "time_step": motion.time_step}
                block = block + block_fn(xe, p, env, state, **moving)
            return block

        out[family] = jax.vmap(stiffness)(x[conn], fam, _previous(scene, conn, motion),
                                          surface_levels(scene, family, conn))
    return out


def _family_closed_form(model, family, elastic_scale=1.0):
    """Sum of the closed-form element matrices (:mod:`jaxnet.closed_form`) of a family's terms in ``model``."""
    terms = [t for t in model if t.term.family == family]

    def block(x, p, env, state, velocity=None, time_step=None):
        total = 0.0
        for t in terms:
            with jax.named_scope(t.name):
                # a moving drag (a time step's) takes its vertices' velocities (m/s) and Δt (s)
                k = t.stiffness(x, p, env, None if state is None else state.get(t.name), velocity, time_step)
                k = elastic_scale * k if t.term.elastic else k
            total = total + k
        return total

    return block


def tangent(x, scene, model, pattern, state=None, elastic_scale=1.0, stiffness="autodiff", motion: Motion | None = None):
    """CSR entries (nnz,) of the tangent K = -d force / dx over the free coordinates.

    ``elastic_scale``: factor on the elastic terms' energy, as in :func:`energy`.

    ``state``: the force terms' global states at x (:func:`states`), if already computed (the solver
    has them from its last evaluation of the force), else computed here.

    ``stiffness``: ``"autodiff"`` (every term by ``jax.jacfwd``) or ``"closed_form"``: the terms with a
    hand-derived stiffness (:mod:`jaxnet.closed_form`) use it, the others autodiff
    (:func:`jaxnet.model.stiffness_paths` says which is which). A Python str.

    ``motion``: in a time step, the past of the velocity-dependent forces (:class:`Motion`).
    """
    return scatter_stiffnesses(tangent_blocks(x, scene, model, state, elastic_scale, stiffness, motion), pattern)


def tangent_blocks(x, scene, model, state=None, elastic_scale=1.0, stiffness="autodiff", motion: Motion | None = None):
    """The element matrices of :func:`tangent` before they are summed into the pattern: {family: (E, 3k, 3k)}
    (N/m), every term of a family summed element by element. Same arguments as :func:`tangent` (no pattern).

    :func:`tangent` is :func:`scatter_stiffnesses` of these. Why they are also offered apart: compiled
    into one program, XLA's CPU backend runs the pair about twice slower than as two programs, apparently
    because it fuses the element computation into the scatter and computes it again entry by entry (an
    ``optimization_barrier`` between them does not help; ``docs/investigations.md`` (XLA's CPU options) has the times of the
    tangent both ways). The static solver's host loop runs the two programs one after the other."""
    if stiffness not in STIFFNESS_PATHS:
        raise ValueError(f"stiffness must be one of {STIFFNESS_PATHS}, not {stiffness!r}")
    by_hand = tuple(t for t in model if stiffness == "closed_form" and t.has_closed_form(motion is not None))
    rest = tuple(t for t in model if t not in by_hand)
    energies = {f: _family_energy(rest, f, elastic_scale) for f in _families(rest, "energy")}
    element_forces = {f: _family_force(rest, f) for f in _families(rest, "force")}
    blocks = {f: _family_closed_form(by_hand, f, elastic_scale) for f in sorted({t.term.family for t in by_hand})}
    # global states (the catch front) are held fixed in the tangent: see the module docstring
    if _families(model, "force"):
        state = jax.lax.stop_gradient(states(x, scene, model) if state is None else state)
    return element_stiffnesses(x, scene, energies, element_forces, state, blocks, motion)
