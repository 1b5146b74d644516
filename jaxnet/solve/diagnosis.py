"""Why a static solve stopped short: what the state it stopped in says about the net, for the failure's message.

A solve that does not converge raises :class:`jaxnet.solve.results.SolveError` naming its reason, its worst
node and where it is. Some nets have no stable equilibrium for any solver to find, and the state a failed
solve stops in often shows why. :func:`hints` reads it and returns sentences that say what was found and
what to try; the static solve appends them to its error.

Struts. The joints of a cable are hinges unless its rope has a bending stiffness
(``Rope(bending_stiffness=EI)``, :mod:`jaxnet.terms.cable_bending`). A cable whose bars have a compression
stiffness (``Rope(ea_compression=...)``) and are pushed into compression, and whose joints are hinges, is a
chain of hinged struts: unless something else holds its joints, it buckles (a compressed straight chain is a
saddle of the energy, and the bent one folds further at no cost), and the net around it has no stable
equilibrium, or only a crumpled one: its bars folded into a zigzag. This is met with sinker bars along the
free bottom of a curtain: the netting above gathers (its meshes close under the weight) and pushes the bar's
ends together. A real rope goes slack in compression (``ea_compression=0``); a rigid bar resists with its
bending stiffness. In ``validation/robustness.py``, the curtains with slack-prone twines (the README's, the
built-in hanging panel) whose sinker bar was a hinged strut stopped on it this way in most currents; a lead
bar with its bending stiffness converges in nearly all (the set's records: a strut is one cause of failure).

Bars that carry little. A bar stretched by only ε, turned by an angle θ in one Newton step, is stretched by
about L0 θ²/2 more than the step's linear model expects: a tension EA θ²/2 it was not meant to take, which
outweighs its own EA ε once θ exceeds √(2ε). Where the net must still turn such bars, each iteration first undoes
the last one's stretch and turns them a little further: the residual stays at a few newtons for hundreds of
iterations (the stretch barrier of large rotations; ``docs/investigations.md`` shows it on FEMNET's
1pelagic_trawl/toto1, whose links of 1 cm and EA 1.6e6 N are stretched by 4e-5). :func:`barely_taut_bars` finds
such bars at the worst node. Where a bar's stretch does not matter (a short link), a lower EA stretches it more
and lets it turn.

Still converging. A solve stopped by its iteration cap while its residual was still falling fast (large nets can
need more iterations than the default cap: the 10⁵-node cage of ``validation/REPORT.md``) needs more iterations, not
another net: :func:`still_falling` says so, with the fall over the last iterations.

Units: m, N.
"""

from __future__ import annotations

import numpy as np

from jaxnet.solve.results import MAX_ITERATIONS

#: a solve stopped by its cap is "still falling" when its largest residual fell by at least this factor over its
#: last quarter of iterations
STILL_FALLING = 2.0

#: a bar is in compression when its strain is below minus this (dimensionless): not roundoff about its rest
#: length
COMPRESSED_STRAIN = 1e-9


def cable_name(scene, cable):
    """The name of cable number ``cable`` of ``scene`` ("cable k" where the scene names none)."""
    names = scene.cable_names or ()
    return names[cable] if cable < len(names) else f"cable {int(cable)}"


def bar_strains(bars, x):
    """(B,) the strain of every bar (dimensionless, < 0 in compression) at positions x (N, 3) (m)."""
    ends = np.asarray(bars.ends)
    X = np.asarray(x, dtype=float)
    return np.linalg.norm(X[ends[:, 1]] - X[ends[:, 0]], axis=1) / np.asarray(bars.rest_length, dtype=float) - 1.0


def compressed_struts(scene, x):
    """The cables whose bars are pushed into compression with a compression stiffness, at positions x (N, 3)
    (m), and whose compressed bars meet at a free hinge (a node of exactly two bars, not fixed on every axis,
    where no cable joint with a bending stiffness resists their turn): hinged struts that buckle. Returns
    ``[(cable name, bars in compression, largest compressive strain, one such joint)]``, the cable with the most
    compressed bars first; [] when there are none."""
    bars = scene.bars
    if bars is None:
        return []
    ends = np.asarray(bars.ends)
    strain = bar_strains(bars, x)
    pushed = (strain < -COMPRESSED_STRAIN) & (np.asarray(bars.ea_compression, dtype=float) > 0.0)
    if not pushed.any():
        return []
    degree = np.bincount(ends.ravel(), minlength=scene.n_nodes)
    held = np.asarray(scene.nodes.fixed).all(axis=1)
    joints = scene.cable_joints
    if joints is not None:  # a joint that bends with a stiffness is no hinge
        stiff = np.asarray(joints.vertices)[np.asarray(joints.stiffness, dtype=float) > 0.0, 1]
        held = held.copy()
        held[stiff] = True
    cable = np.asarray(bars.cable)
    found = []
    for c in np.unique(cable[pushed]):
        mine = pushed & (cable == c)
        hinges = [n for n in np.unique(ends[mine]) if degree[n] == 2 and not held[n]
                  and np.count_nonzero(mine & ((ends[:, 0] == n) | (ends[:, 1] == n))) == 2]
        if hinges:
            found.append((cable_name(scene, c), int(mine.sum()), float(-strain[mine].min()), int(hinges[0])))
    return sorted(found, key=lambda f: -f[1])


#: a bar carries little when its strain lies between 0 and this (dimensionless): one Newton step can then turn it by
#: at most about √(2 × 1e-4) = 0.014 rad before the stretch it makes outweighs its tension
BARELY_TAUT_STRAIN = 1e-4


def barely_taut_bars(scene, x, node):
    """The bars at ``node`` stretched by less than :data:`BARELY_TAUT_STRAIN` (and not slack) at positions x
    (N, 3) (m). Returns ``[(bar, cable name, rest length m, EA N, strain)]``, the least stretched first; [] when
    there are none."""
    bars = scene.bars
    if bars is None:
        return []
    ends = np.asarray(bars.ends)
    rest = np.asarray(bars.rest_length, dtype=float)
    strain = bar_strains(bars, x)
    mine = np.nonzero((ends == node).any(axis=1) & (strain > 0.0) & (strain < BARELY_TAUT_STRAIN))[0]
    cable = np.asarray(bars.cable)
    found = [(int(b), cable_name(scene, cable[b]), float(rest[b]), float(np.asarray(bars.ea_traction, dtype=float)[b]),
              float(strain[b])) for b in mine]
    return sorted(found, key=lambda f: f[4])


def still_falling(eq):
    """(iterations k, residual k iterations before the end, last residual) (N) when ``eq`` stopped at its iteration
    cap with its largest residual fallen at least :data:`STILL_FALLING` times over its last quarter of iterations
    (k of them); else None."""
    it = int(eq.iterations)
    if int(eq.status) != MAX_ITERATIONS or it < 4:
        return None
    history = np.asarray(eq.history, dtype=float)
    k = it // 4
    before, last = float(history[it - k]), float(history[it])
    if np.isfinite(before) and np.isfinite(last) and last * STILL_FALLING <= before:
        return k, before, last
    return None


def hints(scene, eq):
    """Sentences saying what the stopping state of a failed static solve ``eq`` (an
    :class:`~jaxnet.solve.results.Equilibrium`) shows and what to try; [] when nothing is recognised."""
    out = []
    falling = still_falling(eq)
    if falling is not None:
        k, before, last = falling
        out.append(f"the residual was still falling when the iteration cap stopped it ({before:.3g} N -> {last:.3g} N "
                   f"over its last {k} iteration(s)): give it more iterations (max_iter=..., e.g. twice as many)")
    struts = compressed_struts(scene, eq.x)
    if struts:
        name, count, strain, joint = struts[0]
        others = "" if len(struts) == 1 else f" (and {len(struts) - 1} other cable(s))"
        out.append(
            f"cable {name!r}{others} has {count} bars in compression (strain down to {-strain:.3g}) that meet at "
            f"hinges such as node {joint}: its rope has no bending stiffness, so a compressed chain of its bars "
            f"buckles and the net may have no stable equilibrium; a rope goes slack in compression "
            f"(ea_compression=0), a rigid bar resists with its bending stiffness (Rope(bending_stiffness=EI), "
            f"N·m²) (jaxnet.solve.diagnosis explains)")
    taut = barely_taut_bars(scene, eq.x, int(eq.worst_node))
    if taut:
        bar, name, rest, ea, strain = taut[0]
        others = "" if len(taut) == 1 else f" (and {len(taut) - 1} other bar(s) there)"
        out.append(
            f"node {int(eq.worst_node)} hangs on bar {bar} of cable {name!r}{others} (rest length {rest:g} m, EA "
            f"{ea:g} N) stretched by only {strain:.2g}: a Newton step that turns it by more than about "
            f"{np.sqrt(2.0 * strain):.2g} rad stretches it more than its tension, so where the net must still turn "
            f"it the iteration crawls; give it more iterations, or, where its stretch does not matter (a short "
            f"link), a lower EA (jaxnet.solve.diagnosis explains)")
    if not out:
        out.append(GENERAL_HINT)
    return out


#: what to try when a failed solve shows nothing more particular (docs/troubleshooting.md says more)
GENERAL_HINT = ("to try: more iterations (max_iter, --max-iter), a smaller largest step (Newton max_step) for a net "
                "that must turn far from its drawn shape, a start nearer the answer (x0=, e.g. the equilibrium of a "
                "slower current), the autodiff stiffness (--stiffness autodiff) to rule out the closed form; and check "
                "what holds the net where the residual stays (docs/troubleshooting.md)")
