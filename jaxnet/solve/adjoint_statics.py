"""The gradient of a figure of the static equilibrium by the adjoint method, driven from the host.

For a scalar J(x*, θ) of the equilibrium x*(θ) of a scene (θ its float arrays), the implicit function
theorem of :mod:`jaxnet.solve.implicit` gives, with F the out-of-balance force on the free coordinates and
K = -∂F/∂x at x* (N/m),

    dJ/dθ = ∂J/∂θ + λᵀ ∂F/∂θ,        Kᵀ λ = ∂J/∂x                          (λ in m per unit of J / N).

:mod:`jaxnet.solve.implicit` puts that rule into one traced program around a jitted Newton loop, so that
``jax.grad`` of any function of the equilibrium works, under ``jit`` and ``vmap``; its factorisations are
host callbacks, and a program holding a host callback is kept neither by JAX's persistent cache nor by
:mod:`jaxnet.solve.programs` (an executable refers to its callbacks by address). Here the same rule is
driven from Python, as the static solver is (:func:`jaxnet.solve.statics.host_loop`), in pieces that hold
no callback:

1. the equilibrium: the static solver's host loop with the differentiable solve's options
   (:data:`~jaxnet.solve.options.DIFFERENTIABLE`, 1e-8 N), its programs those of every static solve;
2. the figure's value and its derivatives in the free positions and in the scene's float arrays, one
   program (a figure is a pytree: its arrays are arguments of the program, its structure a static one);
3. K at x* (the static solver's tangent program) and its transposed solve on the host, the factorisation
   SuperLU's (:func:`jaxnet.linalg.direct_solver`);
4. λᵀ ∂F/∂x and λᵀ ∂F/∂θ: the residual's reverse-mode derivative, one program ("residual_vjp") kept whole
   on disk as the static solver's are, so that the next process loads it without tracing.

So the gradient costs the forward solve plus one assembly of K, one factorisation and a transposed solve,
and the two reverse-mode programs; and its programs are compiled once per scene shape and terms, in this
process and, with a compilation cache directory set, in the next ones too. Where K is not the exact
Jacobian (a catch: its front moves with the net), λ is refined against the exact transposed product, as
:mod:`jaxnet.solve.implicit` refines its solves.

What it does not do: it is not a JAX transformation, so it is called from Python (a design loop,
:mod:`jaxnet.design.gradient`), not inside a caller's ``jit``, ``vmap`` or ``grad``: those
use :func:`jaxnet.solve.implicit.equilibrium`. Both give the same derivative (``tests/solve/test_adjoint_statics.py``).

Units: m, N; the gradient in units of J per unit of each array of θ.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import linalg
from jaxnet.model import assemble
from jaxnet.scene import checks
from jaxnet.solve import implicit, programs, statics
from jaxnet.solve.options import DIFFERENTIABLE, Newton
from jaxnet.solve.results import CONVERGED, Equilibrium

__all__ = ["Adjoint", "Gradient", "AdjointError"]


class AdjointError(RuntimeError):
    """The adjoint solve Kᵀ λ = ∂J/∂x failed: K is singular at the equilibrium (a mechanism: slack netting
    with no compression or opening stiffness), so the derivative is not unique."""


@dataclasses.dataclass(frozen=True)
class Gradient:
    """A figure's value and gradient at an equilibrium.

    value: J (the figure's units). aux: what the figure returned beside it (None, or a pytree of arrays).
    grad: ∂J/∂(scene's float arrays): a pytree shaped as ``eqx.partition(scene, eqx.is_inexact_array)[0]``
      (None where the scene has no float array), each in J's units per unit of the array.
    equilibrium: the :class:`~jaxnet.solve.results.Equilibrium` (its ``status`` says whether it converged;
      ``grad`` is None where it did not).
    adjoint_residual: the relative residual |Kᵀλ - ∂J/∂x| / |∂J/∂x| of the adjoint solve (exact product).
    """

    value: float
    aux: object
    grad: object
    equilibrium: Equilibrium
    adjoint_residual: float = 0.0


def _partition(scene):
    return eqx.partition(scene, eqx.is_inexact_array)


class _Static:
    """The static half of a figure (no arrays), hashable by value where its fields are (a static argument of
    the figure's program: one compilation per figure structure), else by identity."""

    def __init__(self, value):
        self.value = value
        try:
            self._hash = hash(value)
        except TypeError:
            self._hash = None

    def __hash__(self):
        return id(self.value) if self._hash is None else self._hash

    def __eq__(self, other):
        if not isinstance(other, _Static):
            return NotImplemented
        if self._hash is None or other._hash is None:
            return self.value is other.value
        return self._hash == other._hash and self.value == other.value


def _figure_of(dynamic, static, x_free, params, rest, pattern):
    figure = eqx.combine(dynamic, static.value)
    scene = eqx.combine(params, rest)
    out = figure(assemble.positions(x_free, scene, pattern), scene)
    value, aux = out if isinstance(out, tuple) else (out, None)
    return jnp.asarray(value, float), aux


def _figure_value(dynamic, x_free, params, rest, pattern, static):
    """J and aux at the free positions ``x_free`` of the scene (params, rest)."""
    return _figure_of(dynamic, static, x_free, params, rest, pattern)


def _figure_value_and_grads(dynamic, x_free, params, rest, pattern, static):
    """(J, aux), (∂J/∂x_free, ∂J/∂params)."""
    return jax.value_and_grad(lambda x, p: _figure_of(dynamic, static, x, p, rest, pattern), argnums=(0, 1),
                              has_aux=True)(x_free, params)


# the figure is the caller's (a pytree of its arrays and a static structure): compiled by jax.jit, whose
# persistent cache (keyed by the lowered program) keeps it between processes
_figure_value_jit = programs.jit(_figure_value, static_argnames=("static",))
_figure_grads_jit = programs.jit(_figure_value_and_grads, static_argnames=("static",))


def _residual_vjp(x_free, params, rest, pattern, lam, model):
    """(λᵀ ∂F/∂x, λᵀ ∂F/∂params) for the out-of-balance force F on the free coordinates (N)."""
    structure = implicit.Structure(pattern=pattern, model=model)

    def force(x, p):
        return implicit.residual(x, eqx.combine(p, rest), structure)

    _, pullback = jax.vjp(force, x_free, params)
    g_x, g_params = pullback(lam)
    # the leaves, in params' order: a program kept on disk comes back with its output's structure unpickled, and
    # a scene's dataclass structure does not survive pickling (the caller puts them back in its own)
    return g_x, jax.tree.leaves(g_params)


_residual_vjp_jit = programs.jit(_residual_vjp, static_argnames=("model",))


class Adjoint:
    """Value and gradient of figures of the static equilibrium of scenes shaped as ``reference``
    (the same nodes, fixities, connectivity and terms: a family of designs).

    Args:
      reference: a concrete :class:`~jaxnet.scene.Scene`: its active terms and the tangent's pattern are
        computed once (:func:`jaxnet.solve.implicit.structure_of`).
      solver: the forward solve's options (:class:`~jaxnet.solve.options.Newton`); default
        :data:`~jaxnet.solve.options.DIFFERENTIABLE` (1e-8 N: the derivative is that of the root, as
        accurate as the solve). Its ``stiffness`` also chooses the path of K in the adjoint solve.

    A *figure* is a callable ``figure(X, scene) -> J`` or ``-> (J, aux)`` (X the (N, 3) positions, m), a pytree
    (an equinox Module: its arrays are arguments of the compiled program, the rest its structure), written
    in jnp: :mod:`jaxnet.design.gradient` wraps a design objective into one.
    """

    def __init__(self, reference, solver: Newton | None = None):
        self.structure = implicit.structure_of(reference)
        self.solver = solver or DIFFERENTIABLE
        pattern = self.structure.pattern
        self._free = np.asarray(pattern.free)
        self._indptr, self._indices = np.asarray(pattern.indptr), np.asarray(pattern.indices)
        self._pattern = jax.device_put(pattern)
        self._programs = {}  # scene signature -> the static solver's compiled programs
        self._fixed = np.asarray(reference.nodes.fixed)

    @property
    def model(self):
        """The active terms (static), those of the reference."""
        return self.structure.model

    def _pieces(self, start, scene):
        # the static solver's programs for this scene's shapes: looked up once per shape, not at every solve
        leaves, treedef = jax.tree.flatten(scene)
        signature = (treedef, tuple((np.shape(v), str(getattr(v, "dtype", type(v)))) for v in leaves))
        if signature not in self._programs:
            self._programs[signature] = statics.compile_pieces(start, scene, self._pattern, self.model,
                                                               self.solver.stiffness, method=self.solver.method)
        return self._programs[signature]

    def solve(self, scene, x0=None) -> Equilibrium:
        """The equilibrium of ``scene`` (validated) from ``x0`` ((N, 3) m; default the scene's positions) by the
        static solver's host loop with this object's options; read its ``status``."""
        params, rest = self._on_device(scene)
        return self._solve(eqx.combine(params, rest), x0)

    def _on_device(self, scene):
        """``scene`` validated, split into its float arrays (what the gradient is of: as the caller's scene
        holds them, before a Python number on the device would become one) and the rest, each put on the
        device once (every program takes them)."""
        checks.validate(scene)
        if scene.n_nodes != self._fixed.shape[0] or not np.array_equal(np.asarray(scene.nodes.fixed), self._fixed):
            raise ValueError(f"Adjoint: the scene ({scene.n_nodes} nodes) is not of the reference's family: its nodes "
                             f"or their fixities differ from the reference's ({self._fixed.shape[0]} nodes); make "
                             "an Adjoint of this scene")
        params, rest = _partition(scene)
        return jax.device_put(params), jax.device_put(rest)

    def _solve(self, scene, x0):
        start = statics.start_coordinates(scene, self._free, x0, who="Adjoint")
        return statics.host_loop(start, scene, self._pattern, self.model, self.solver, self._pieces(start, scene))

    def value(self, figure, scene, x0=None):
        """(J, aux, equilibrium) of ``figure`` at the equilibrium of ``scene`` (J NaN where it did not
        converge)."""
        params, rest = self._on_device(scene)
        scene = eqx.combine(params, rest)
        eq = self._solve(scene, x0)
        dynamic, static = eqx.partition(figure, eqx.is_array)
        x_free = jnp.asarray(eq.x).ravel()[self._free]
        value, aux = _figure_value_jit(dynamic, x_free, params, rest, self._pattern, static=_Static(static))
        value = float(value) if int(eq.status) == CONVERGED else float("nan")
        return value, aux, eq

    def value_and_grad(self, figure, scene, x0=None) -> Gradient:
        """:class:`Gradient` of ``figure`` at the equilibrium of ``scene`` from ``x0`` ((N, 3) m; default the
        scene's positions). Where the solve does not converge, ``grad`` is None and ``value`` NaN: read
        ``equilibrium.status``. Raises :class:`AdjointError` when K is singular at the equilibrium."""
        params, rest = self._on_device(scene)
        scene = eqx.combine(params, rest)
        eq = self._solve(scene, x0)
        if int(eq.status) != CONVERGED:
            return Gradient(value=float("nan"), aux=None, grad=None, equilibrium=eq)
        dynamic, static = eqx.partition(figure, eqx.is_array)
        x_free = jnp.asarray(eq.x).ravel()[self._free]
        (value, aux), (g_x, g_params) = _figure_grads_jit(dynamic, x_free, params, rest, self._pattern,
                                                          static=_Static(static))
        residual, g_force = self._adjoint(x_free, params, rest, scene, np.asarray(g_x))
        grad = jax.tree.map(lambda a, b: a + b, g_params, g_force)
        return Gradient(value=float(value), aux=aux, grad=grad, equilibrium=eq, adjoint_residual=residual)

    def _residual_vjp(self, x_free, params, rest, lam):
        args = (x_free, params, rest, self._pattern, jnp.asarray(lam))
        program = programs.obtain("residual_vjp", _residual_vjp_jit, args, {"model": self.model})
        structure = jax.tree.structure(params)

        def vjp(v):
            g_x, leaves = program(x_free, params, rest, self._pattern, jnp.asarray(v))
            return g_x, jax.tree.unflatten(structure, leaves)

        return vjp

    def _adjoint(self, x_free, params, rest, scene, g):
        """For λ solving Kᵀ λ = g at the equilibrium (refined against the exact transposed product where K is
        not the exact Jacobian): the relative residual of that product, and λᵀ ∂F/∂params."""
        start = np.asarray(x_free)
        pieces = self._pieces(start, scene)
        load = pieces["loads"](scene)
        zero = jnp.zeros_like(load)
        state = pieces["evaluate"](x_free, zero, load, 1.0, scene, self._pattern, pieces["states"], None)[4]
        data = np.asarray(pieces["scatter"](pieces["tangent"](x_free, state, 1.0, scene, self._pattern, None),
                                            self._pattern))
        factor = linalg.direct_solver(self._indptr, self._indices)
        lam, ok = factor.solve(data, g, transpose=True)
        if not ok or not np.all(np.isfinite(lam)):
            raise AdjointError("adjoint solve: the tangent K is singular at the equilibrium (a mechanism: slack "
                               "twines with no compression or opening stiffness); the derivative is not unique "
                               "there. Give the netting an opening or compression stiffness, or a load that "
                               "tensions it")
        scale = max(float(np.linalg.norm(g)), 1e-300)
        vjp = self._residual_vjp(x_free, params, rest, lam)

        # the exact transposed product's misfit g - Jᵀλ (J = -∂F/∂x), from the same program as λᵀ ∂F/∂params
        g_x, g_params = vjp(lam)
        r = g + np.asarray(g_x)
        if not self.structure.exact_tangent:
            for _ in range(implicit.REFINEMENTS):
                if np.linalg.norm(r) <= implicit.REFINE_RTOL * scale:
                    break
                lam = lam + factor.apply(r, transpose=True)
                g_x, g_params = vjp(lam)
                r = g + np.asarray(g_x)
        return float(np.linalg.norm(r) / scale), g_params
