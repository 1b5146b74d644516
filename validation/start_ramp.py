"""The start of a dynamic run: the cage in waves (``jaxnet.scenes.cage_in_waves(step=1.6)``, 2 m 6 s waves)
started from its static equilibrium, with the run's default start ramp (the waves and the collar's heave grown in
together over one wave period, C² envelope) and as the built-in scene ran before that ramp existed (the waves at
full height from t = 0, the collar's heave alone ramped by a half-cosine over 2 s).

    python validation/start_ramp.py

Prints per start: the static vertical reaction (N), the first two records' (t = 0 and 0.1 s), the largest
departure from the static one over the first second, and the swing (largest minus smallest) of the vertical
reaction once the waves are at full height (6-12 s), to weigh it against. A benchmark, not a test
(``tests/test_dynamics.py`` holds the default start to a bound).
"""
import equinox as eqx
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401
from jaxnet.water import forcing
from jaxnet.scenes import cage_in_waves
from jaxnet.solve import dynamics
from jaxnet.solve.statics import solve

case = cage_in_waves(step=1.6)
default = dynamics.with_start_ramp(case.scene, case.time.loading)[:2]
heave = case.time.loading.motions[0]
before = (case.scene, eqx.tree_at(lambda ld: (ld.motions, ld.ramp), case.time.loading,
                                  ((forcing.PrescribedMotion(heave.nodes, eqx.tree_at(lambda m: m.ramp, heave.motion,
                                                                                      jnp.asarray(2.0))),), 0.0),
                                  is_leaf=lambda v: v is None))
print("| start | static Fz N | Fz at 0 s | Fz at 0.1 s | largest departure over 0-1 s N | swing 6-12 s N |")
print("|---|---|---|---|---|---|")
for name, (scene, loading) in (("start ramp (default, one period)", default), ("before: heave ramped over 2 s", before)):
    eq = solve(dynamics.scene_at(scene, loading, 0.0), case.solver)
    static = np.asarray(eq.reaction(scene)).sum(axis=0)
    run = dynamics.simulate(scene, 12.0, case.time.solver, loading, record_every=0.1, x0=np.asarray(eq.x))
    z, t = run.figures["reaction_total_N"][:, 2], run.times
    full = z[t >= 6.0]
    first = z[t <= 1.0 + 1e-9]
    print(f"| {name} | {static[2]:.0f} | {first[0]:.0f} | {first[1]:.0f} | {np.abs(first - static[2]).max():.0f} | "
          f"{full.max() - full.min():.0f} |")
