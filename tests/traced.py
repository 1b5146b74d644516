"""What a scene's Newton program traces: the lowered (not compiled) program and the term names in it.

Shared by the tests that check a scene compiles only the terms it uses."""

import re

import numpy as np

import jaxnet as jn
from jaxnet import model
from jaxnet.model import assemble
from jaxnet.solve import newton
from jaxnet.terms import term as term_lib

#: a location of the lowered program with its name stack, e.g. jit(newton_loop)/vmap(netting_drag)/...
NAMED_LOCATION = re.compile(r'loc\("([^"]+)"\(')


def lowered_text(scene, dynamic=False):
    """The scene's whole Newton program, lowered with debug information (nothing is compiled); ``dynamic``: that
    of a time step (0.01 s from rest)."""
    from jaxnet.solve import dynamics

    m = model.active_terms(scene, dynamic=dynamic)
    p = assemble.build_pattern(scene, m)
    x = np.asarray(scene.nodes.position, dtype=float)
    x0 = x.ravel()[np.asarray(p.free)]
    step = None
    if dynamic:
        step = dynamics.TimeStep(x, np.zeros_like(x), np.float64(0.01), dynamics.lumped_masses(scene)[0],
                                 np.zeros_like(x))
    return newton.newton_loop_jit.lower(x0, scene, p, model=m, solver=jn.Newton(), step=step).as_text(debug_info=True)


def traced_terms(scene):
    """Names of registered terms found in the name stacks of the scene's lowered Newton program."""
    words = set()
    for name in NAMED_LOCATION.findall(lowered_text(scene)):
        if "/" in name:
            words.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", name))
    return words & {t.name for t in term_lib.registered()}
