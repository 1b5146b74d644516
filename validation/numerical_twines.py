"""FEMNET's numerical-twine cases (``0simple/nr_*``: ``input netting2ropes``) solved by jaxnet: a table.

    python validation/numerical_twines.py [--data /work/shared/femnet-corpus/0simple] [--cases nr_20_0_0_3_2 ...]

Per case: FEMNET's mesh counts (its ``.mdg``: nodes, bars of numerical twines, bars of the sinker rope) and
jaxnet's (its mesher from the ``.don``); then FEMNET's total force (its current code, ``ANSWERS.md``) and
jaxnet's, with Newton's iterations, three ways:

* ``jaxnet mesh``: the case as :func:`jaxnet.io.femnet.read_don` reads it;
* ``+ FEMNET's 2nd rope``: that scene with the copy of the sinker rope (cable 5) that FEMNET's mesher leaves
  in its ``.mdg`` (:func:`with_femnets_second_rope`; :mod:`jaxnet.io.femnet.twines` says why);
* ``FEMNET mesh``: FEMNET's ``.mdg`` read by :func:`jaxnet.io.femnet.read_mdg`.

The last two should agree with each other (same mesh) and with FEMNET (same physics), the first differs from
FEMNET by that second rope.
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

#: FEMNET's total force (N) of its current code, and its iterations (ANSWERS.md)
FEMNET = {
    "nr_10_0_0_3_2": ((147.11528, 0.00744, -56.86456), 3029),
    "nr_20_025_025_3_2": ((158.29060, -0.01583, -57.63982), 2031),
    "nr_20_05_0_3_2": ((166.53209, 0.86081, -61.58396), 2567),
    "nr_20_0_0_3_2": ((158.10718, -0.00104, -60.45722), 2155),
    "nr_5_0_0_1_1": ((176.60294, -0.03090, -58.32616), 7398),
}

_FIELDS = ("ends", "rest_length", "ea_traction", "ea_compression", "diameter", "density", "cable", "cd_normal",
           "tangential_ratio")


def with_femnets_second_rope(case, k=4, n=57):
    """(scene, number of bars added): ``case`` (:func:`~jaxnet.io.femnet.read_don`'s) with FEMNET's copy of cable
    k + 1, meshed before the panel in n bars: its original bar from each of its own nodes (at j / n from its end
    1) to the next node along it, which is a twine's border node where FEMNET inserted one there, of rest length
    its share of the cable times the cable's length (FEMNET's ``bar_creation_per_element_around_panel``)."""
    import equinox as eqx

    from jaxnet.io import femnet
    from jaxnet.scene import Bars

    s, b = case.scene, case.scene.bars
    x = np.asarray(s.nodes.position)
    nodes = np.asarray(case.net.layout.cable_nodes[f"cable {k + 1}"])
    rope = femnet.parse_don(case.info["source"]).cables[k]
    if np.linalg.norm(x[nodes[0]] - rope.ends[0]) > np.linalg.norm(x[nodes[-1]] - rope.ends[0]):
        nodes = nodes[::-1]
    along = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x[nodes], axis=0), axis=1))]
    frac = along / along[-1]
    own = np.array([i for i in range(len(nodes) - 1) if abs(frac[i] * n - round(frac[i] * n)) < 1e-6])
    row = int(np.flatnonzero(np.asarray(b.cable) == k)[0])
    extra = {f: np.repeat(np.asarray(getattr(b, f))[row:row + 1], len(own), axis=0) for f in _FIELDS}
    extra["ends"] = np.stack([nodes[own], nodes[own + 1]], axis=1)
    extra["rest_length"] = (frac[own + 1] - frac[own]) * rope.material["l0"].value
    bars = Bars(**{f: np.concatenate([np.asarray(getattr(b, f)), extra[f]]) for f in _FIELDS})
    return eqx.tree_at(lambda t: t.bars, s, bars), len(own)


def _solved(scene, case):
    from jaxnet.io import femnet
    from jaxnet.solve.statics import solve

    eq = solve(scene, case.solver, throw=False)
    total = np.array(femnet.femnet_figures(scene, eq, case.info["symmetry_axes"])["total_force_N"])
    return total, int(eq.iterations), bool(eq.converged)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=pathlib.Path, default=pathlib.Path("/work/shared/femnet-corpus/0simple"))
    parser.add_argument("--cases", nargs="*", default=sorted(FEMNET))
    args = parser.parse_args(argv)

    from jaxnet.io import femnet

    print("| case | mesh | nodes | twine bars | rope 5 bars | total force X Y Z (N) | vs FEMNET x, z | "
          "iterations |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.cases:
        don, mdg = args.data / f"{name}.don", args.data / f"{name}.mdg"
        ref, ref_iter = FEMNET[name]
        ref = np.array(ref)
        case = femnet.read_don(don)
        on_mdg = femnet.read_mdg(mdg, don)
        theirs = np.bincount(np.asarray(on_mdg.scene.bars.cable))
        mine = np.bincount(np.asarray(case.scene.bars.cable))
        doubled, _ = with_femnets_second_rope(case)
        print(f"| {name} | FEMNET | {on_mdg.scene.n_nodes} | {theirs[-1]} | {theirs[4]} | "
              f"{' '.join(f'{v:.5f}' for v in ref)} | | {ref_iter} |")
        for label, scene, counts in (("jaxnet mesh", case.scene, mine),
                                     ("+ FEMNET's 2nd rope", doubled, np.bincount(np.asarray(doubled.bars.cable))),
                                     ("FEMNET mesh", on_mdg.scene, theirs)):
            total, iterations, converged = _solved(scene, case)
            rel = 100 * (total / ref - 1)
            print(f"| | {label} | {scene.n_nodes} | {counts[-1]} | {counts[4]} | "
                  f"{' '.join(f'{v:.5f}' for v in total)} | {rel[0]:+.3f} %, {rel[2]:+.3f} % | "
                  f"{iterations}{'' if converged else ' (not converged)'} |")


if __name__ == "__main__":
    main()
