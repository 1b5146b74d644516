"""Robustness set of the static solver: does it converge, in how many iterations, at what cost, on every net?

    python validation/robustness.py [--size test|quick|full] [--only WORDS] [--out PATH] [--resume] [--list]
    python validation/robustness.py --compare OLD.json [NEW.json]

The set every change to the static solver (``jaxnet/solve``) is judged on. Each case is solved once with
``jaxnet.solve_static(..., throw=False)`` from its drawn start (the stress-free shape the net is described
in: flat panels; the stability suite's perturbed starts as that suite makes them), to the library's
tolerance (:data:`jaxnet.solve.options.TOL_N`, 1e-3 N), with at most :data:`MAX_ITERATIONS` Newton
iterations: a case that needs more is a failure here, and one bad case cannot take the whole run. The
other Newton options are the library's (:data:`jaxnet.solve.options.STATIC`), or a case's own where it
has them (a FEMNET case's displacement limit); only the tolerance and the cap are replaced.

The cases, family by family (``--size``: ``test`` a handful of tiny cases for the unit tests; ``quick`` the
panels at about 10² and 10³ nodes, the cage at 10³, the cod-end, FEMNET's cases and the stability suite at
its test size; ``full`` everything):

- ``readme``: the README's panel (40 x 40 meshes of l0 = 0.025 m, EA 2000 N, twine diameter 1.5 mm, drawn
  in the vertical x-z plane, a headline along its top, held at its two top corners), with its lead sinker
  bar (a 10 mm lead rod, 0.89 kg/m, EI 7.9 N·m²) or without it (the bottom border free).
- ``hanging``: :func:`jaxnet.scenes.hanging_panel` (the same curtain, its sinker bar of 1 kg/m, a lead rod
  with its bending stiffness), with the sinker or with the same bar weightless (``sinker_kg_per_m=0``, the
  1 kg/m rod's bending stiffness: the bar keeps the bottom's width).

  The sinker bars bend with the stiffness of a lead rod (:func:`jaxnet.materials.rod_bending_stiffness`).
  Before, they were chains of hinged struts: the netting, which gathers, pushed their ends together and they
  folded into a zigzag (:mod:`jaxnet.solve.diagnosis`), a net with no stable equilibrium; the baseline
  records (``robustness_before.json``) and the set's records before this change hold those runs.
- ``framed``: :func:`jaxnet.scenes.framed_panel` (40 x 40 meshes, horizontal, held along its border), with
  its 5 kg central sinker or without it (its own weight only).

  Every panel has the physical twine, ``ea_compression=0`` (slack allowed), and about 10², 10³ or 10⁴
  nodes (the meshing step: the mesher holds about :data:`NODES_PER_STEP2` nodes per step² of netting),
  in still water and in uniform currents of :data:`SPEEDS` m/s at :data:`ANGLES` degrees from the panel's
  plane. The current's direction, for the vertical panels (x-z plane): horizontal, (cos θ, sin θ, 0),
  θ = 0 along the headline, 90° normal to the panel. For the horizontal framed panel the direction turns
  in the vertical x-z plane, (cos θ, 0, -sin θ): θ = 0 along the panel (x), 90° normal to it, downwards
  (with the weight: the angle of attack of a flow meeting a panel, not a sea current).
- ``cage``: :func:`jaxnet.scenes.fish_cage` at meshing steps :data:`CAGE_STEPS` (step 0.5 m: 1161 nodes;
  nodes grow as 1/step²: to about 1.2·10⁵) in currents of :data:`CAGE_SPEEDS` m/s.
- ``codend``: :func:`jaxnet.scenes.codend` (its defaults: 100 x 50 meshes, 1.5 m/s) holding
  :data:`CATCHES_M3` m³ of catch.
- ``femnet``: every ``.don`` file in ``tests/data/femnet/`` and under ``../shared/femnet-corpus/`` (files
  of identical contents once) that :func:`jaxnet.io.femnet.read_don` reads; those it does not read are
  listed as "does not read" with the first line of the reader's message, and are not solver failures.
- ``stability``: the statics cases of the stability suite (:func:`validation.stability.catalogue`: its
  dynamics family excluded), from its flat and perturbed starts, at its ``test`` size (``quick``) or its
  ``full`` size; a run is *as expected* when its outcome is one the case accepts
  (:func:`validation.stability.accepted`: convergence, or the named stop its note explains).

Per case, one row of a Markdown table: name, nodes, converged, stop reason, Newton iterations,
factorisations, wall time (s) split into tangent assembly, factorisation (and solves), residual evaluation
and the rest (wall - compile - those three: the host loop's bookkeeping), the mean time of one
factorisation, compile time (about 0 when an earlier case had the same shape and terms), and the peak
resident memory of the case (the process's peak reset before it: ``/proc/self/clear_refs``, read from
``VmHWM``; where that is not possible, the process's peak so far, ``ru_maxrss``, as the record says). Then
per family: the fraction converged, the median and largest iteration counts over converged cases, and
how many of those took more than 25 and more than 60 iterations.

The records are appended as JSON lines to ``--out`` (default ``validation/results/robustness.json``) as each
case ends; ``--resume`` skips the cases already there. ``--compare OLD.json [NEW.json]`` (NEW default:
``--out``) prints, per case, converged and iterations before and after, and both summaries side by side.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import hashlib
import json
import math
import pathlib
import resource
import sys
import time
from typing import Callable

import numpy as np

TITLE = "Robustness set of the static solver"

#: the Newton iterations every run may take: a case that needs more is a failure of the set
MAX_ITERATIONS = 500
#: the panels' currents (m/s) and their angles from the panel's plane (degrees)
SPEEDS = (0.0, 0.1, 0.3, 1.0, 2.0)
ANGLES = (0, 30, 60, 90)
#: the panels: meshes a side, mesh side (m), and the node counts aimed at, per size
PANEL_MESHES, PANEL_L0 = 40, 0.025
PANEL_NODES = {"test": (100,), "quick": (100, 1000), "full": (100, 1000, 10_000)}
#: nodes per step² of netting that the mesher's lattice holds (benchmarks/statics.py)
NODES_PER_STEP2 = 1.15
#: the fish cage's meshing steps (m) per size (0.5: 1161 nodes; nodes ~ 1/step²) and its currents (m/s)
CAGE_STEPS = {"test": (), "quick": (0.5,), "full": (0.5, 0.23, 0.11, 0.05)}
CAGE_SPEEDS = (0.25, 0.5, 1.0)
#: the cod-end's catches (m³, the whole cod-end)
CATCHES_M3 = (0.05, 0.1, 0.3, 1.0)
#: the stability suite's size per size of this set
STABILITY_SIZE = {"test": "test", "quick": "test", "full": "full"}
#: the stability suite's families that are dynamics runs (not part of this set)
STABILITY_DYNAMIC = ("time step",)
ROOT = pathlib.Path(__file__).resolve().parent.parent
#: where FEMNET's cases are looked for (``.don`` files, recursively)
FEMNET_DIRS = (ROOT / "tests" / "data" / "femnet", ROOT.parent / "shared" / "femnet-corpus")
DEFAULT_OUT = ROOT / "validation" / "results" / "robustness.json"
FAMILIES = ("readme", "hanging", "framed", "cage", "codend", "femnet", "stability")
CONVERGED = "converged"
#: the prefixes of the reasons of runs that did not reach the solver
NOT_READ, REFUSED, ERROR = "does not read", "SceneError", "error"
SIZES = ("test", "quick", "full")


# -- the cases -------------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Setup:
    """What one run solves: the scene, the case's own Newton options (None: the library's), the start
    positions (None: the scene's drawn positions)."""

    scene: object
    newton: object | None = None
    x0: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class RobustnessCase:
    """One case: its unique name, its family (:data:`FAMILIES`), ``build() -> Setup``, and the outcomes it
    accepts (a reason starting with one of them; :func:`validation.stability.accepted`)."""

    name: str
    family: str
    build: Callable[[], Setup]
    expect: tuple = (CONVERGED,)


class NotRead(Exception):
    """FEMNET's reader refused a ``.don`` file (the message: the first line of its error)."""


def panel_step(nodes, meshes=PANEL_MESHES, l0=PANEL_L0):
    """The meshing step (m) that gives a square panel of ``meshes`` square meshes about ``nodes`` nodes."""
    width = meshes * l0 * math.sqrt(2.0)
    return width / math.sqrt(nodes / NODES_PER_STEP2)


def physical_twine():
    """The panels' twine: polyamide, EA 2000 N, 1.5 mm, slack in compression (EA_c = 0)."""
    from jaxnet.net import Twine

    return Twine(l0=PANEL_L0, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=0.0)


def environment(speed, direction):
    """A uniform current of ``speed`` (m/s) along ``direction``; still water for speed 0."""
    from jaxnet.net import Environment

    if not speed:
        return Environment()
    return Environment(current_speed=float(speed), current_direction=np.asarray(direction, dtype=float))


def vertical_panel_direction(angle):
    """A panel in the x-z plane: the horizontal current ``angle`` degrees from it (0: along x, 90: along y)."""
    a = math.radians(angle)
    return (math.cos(a), math.sin(a), 0.0)


def horizontal_panel_direction(angle):
    """A panel in the x-y plane: the current ``angle`` degrees from it, turning down in the x-z plane."""
    a = math.radians(angle)
    return (math.cos(a), 0.0, -math.sin(a))


def readme_panel(nodes, speed, angle, sinker):
    """The README's panel (``README.md``, Python API) of about ``nodes`` nodes in a current; without its
    sinker bar when ``sinker`` is false."""
    from jaxnet.net import Net, Rope

    n, l0 = PANEL_MESHES, PANEL_L0
    w = n * l0 * math.sqrt(2.0)
    net = Net(environment=environment(speed, vertical_panel_direction(angle)))
    wall = net.panel("wall", corners=[(0, 0, -w, 0, 0), (w, 0, -w, n, -n), (w, 0, 0, 2 * n, 0), (0, 0, 0, n, n)],
                     twine=physical_twine(), step=panel_step(nodes))
    net.cable("headline", along=wall.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    if sinker:
        net.cable("sinker bar", along=wall.side(0),
                  rope=Rope(ea=1e5, diameter=0.01, density=11340.0, ea_compression=1e5, bending_stiffness=7.9))
    net.fix(wall.corner(2))
    net.fix(wall.corner(3))
    return net.build()


def hanging(nodes, speed, angle, sinker):
    """:func:`jaxnet.scenes.hanging_panel` of about ``nodes`` nodes in a current; its sinker bar of 1 kg/m,
    or weightless (0 kg/m) when ``sinker`` is false, bending as the 1 kg/m lead rod in both. Rebuilt from the
    case's ``net``, its environment set."""
    from jaxnet.materials import rod_bending_stiffness
    from jaxnet.scenes import hanging_panel

    rod = math.sqrt(4.0 * 1.0 / (math.pi * 11340.0))  # the diameter (m) of a lead rod of 1 kg/m
    net = hanging_panel(meshes=PANEL_MESHES, l0=PANEL_L0, step=panel_step(nodes), twine=physical_twine(),
                        sinker_kg_per_m=1.0 if sinker else 0.0,
                        sinker_bending_stiffness=rod_bending_stiffness(rod)).net
    net.environment = environment(speed, vertical_panel_direction(angle))
    return net.build()


def framed(nodes, speed, angle, sinker):
    """:func:`jaxnet.scenes.framed_panel` of about ``nodes`` nodes in a current; its 5 kg sinker, or none.
    Rebuilt from the case's ``net``, its environment set."""
    from jaxnet.scenes import framed_panel

    net = framed_panel(meshes=PANEL_MESHES, l0=PANEL_L0, step=panel_step(nodes), twine=physical_twine(),
                       sinker_kg=5.0 if sinker else 0.0).net
    net.environment = environment(speed, horizontal_panel_direction(angle))
    return net.build()


PANELS = {"readme": readme_panel, "hanging": hanging, "framed": framed}


def panel_currents(size):
    """(speed, angle) pairs of the panels: still water once, then every speed at every angle."""
    if size == "test":
        return [(1.0, 90)]
    return [(0.0, 0)] + [(s, a) for s in SPEEDS if s for a in ANGLES]


def panel_name(family, nodes, speed, angle, sinker):
    current = "still" if not speed else f"{speed:g}m/s {angle}deg"
    return f"{family} n{nodes} {current} {'sinker' if sinker else 'no-sinker'}"


def panel_cases(size):
    cases = []
    for family, build in PANELS.items():
        if size == "test" and family != "readme":
            continue
        for nodes in PANEL_NODES[size]:
            for sinker in ((True,) if size == "test" else (True, False)):
                for speed, angle in panel_currents(size):
                    cases.append(RobustnessCase(panel_name(family, nodes, speed, angle, sinker), family,
                                                _setup_of(build, nodes, speed, angle, sinker)))
    return cases


def _setup_of(build, *args):
    return lambda: Setup(build(*args))


def _case_setup(case):
    """A :class:`jaxnet.case.Case`'s scene with its own solver options."""
    return Setup(case.scene, newton=case.solver)


def cage_cases(size):
    from jaxnet.scenes import fish_cage

    return [RobustnessCase(f"cage step{step:g} {speed:g}m/s", "cage",
                           lambda step=step, speed=speed: _case_setup(fish_cage(step=step, current=speed)))
            for step in CAGE_STEPS[size] for speed in CAGE_SPEEDS]


def codend_cases(size):
    from jaxnet.scenes import codend

    if size == "test":
        return []
    return [RobustnessCase(f"codend catch{volume:g}m3", "codend",
                           lambda volume=volume: _case_setup(codend(catch_m3=volume)))
            for volume in CATCHES_M3]


def femnet_files(dirs=FEMNET_DIRS):
    """(name, path) of every ``.don`` file under ``dirs``, each content once (the first path found)."""
    seen, files = set(), []
    for root in dirs:
        root = pathlib.Path(root)
        if not root.is_dir():
            continue
        for path in sorted(root.rglob("*.don")):
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
            if digest in seen:
                continue
            seen.add(digest)
            name = path.relative_to(root).with_suffix("").as_posix()
            files.append((name if root == FEMNET_DIRS[0] else f"corpus/{name}", path))
    return files


def read_femnet(path, name):
    """The setup of a ``.don`` file (its own Newton options); :class:`NotRead` when the reader refuses it
    (the message names the file by ``name``, not by where this checkout keeps it)."""
    from jaxnet.io import femnet

    try:
        loaded = femnet.read_don(path)
    except Exception as error:  # noqa: BLE001 -- any refusal of the reader: "does not read", not a solver failure
        raise NotRead(_first_line(error).replace(str(path), f"{name}.don")) from error
    return _case_setup(loaded)


def femnet_cases(size, dirs=FEMNET_DIRS):
    files = femnet_files(dirs)
    if size == "test":
        files = [(n, p) for n, p in files if n == "links_hub"]
    return [RobustnessCase(f"femnet {name}", "femnet", functools.partial(read_femnet, path, name))
            for name, path in files]


def stability_cases(size):
    """The stability suite's statics cases from each of its starts (names "stability CASE (START)")."""
    from validation import stability

    if size == "test":
        chosen = [c for c in stability.catalogue() if c.name == "framed EA 1e+04 N"]
        starts = ("flat",)
    else:
        chosen = [c for c in stability.catalogue()
                  if c.family not in STABILITY_DYNAMIC and (size == "full" or not c.full_only)]
        starts = stability.STARTS
    return [RobustnessCase(f"stability {c.name} ({start})", "stability",
                           functools.partial(stability_setup, c, start, STABILITY_SIZE[size]), expect=c.expect)
            for c in chosen for start in starts]


def stability_setup(case, start, size):
    """A stability case's problem at ``size`` from ``start`` (its perturbed start as the suite makes it)."""
    from validation import stability

    problem = case.build(size)
    if problem.dynamic is not None:
        raise ValueError(f"stability case {case.name!r} is a dynamics run, not part of the robustness set")
    x0 = None if start == "flat" else stability.perturbed_start(problem.scene)[0]
    return Setup(problem.scene, newton=problem.newton, x0=x0)


def cases(size):
    """Every case of the set at ``size``, family by family."""
    if size not in SIZES:
        raise ValueError(f"size must be one of {SIZES}, got {size!r}")
    return (panel_cases(size) + cage_cases(size) + codend_cases(size) + femnet_cases(size)
            + stability_cases(size))


# -- running a case --------------------------------------------------------------------------------------------


def reset_peak_memory():
    """Reset the process's peak resident memory (``VmHWM``); False where the kernel does not allow it."""
    try:
        pathlib.Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


def peak_memory_mb(reset):
    """(peak resident memory in MB, how it was measured)."""
    if reset:
        try:
            for line in pathlib.Path("/proc/self/status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024, "VmHWM"
        except OSError:
            pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "ru_maxrss (the process's peak so far)"


#: the static method every case is solved with (``--method``; None: each case's own, the library's default)
METHOD = None


def newton_options(setup):
    """The case's Newton options (the library's where it has none) with the set's tolerance and cap (and the
    method of ``--method``, where given)."""
    from jaxnet.solve.options import STATIC, TOL_N

    method = {} if METHOD is None else {"method": METHOD}
    return dataclasses.replace(setup.newton or STATIC, tol=TOL_N, max_iter=MAX_ITERATIONS, **method)


def _first_line(error):
    text = str(error).strip()
    return f"{type(error).__name__}: {text.splitlines()[0] if text else ''}"


def _finite(*arrays):
    return all(bool(np.all(np.isfinite(np.asarray(a, dtype=float)))) for a in arrays)


def solve_record(eq):
    """The fields of a record that a solve's :class:`~jaxnet.solve.results.Equilibrium` gives."""
    t = eq.timing
    other = t.wall_s - t.compile_s - t.assembly_s - t.factorisation_s - t.evaluation_s
    return dict(converged=eq.converged, reason=eq.reason, iterations=int(eq.iterations),
                residual_N=float(eq.residual_N), worst_node=int(eq.worst_node),
                factorisations=t.factorisations, fallbacks=t.fallbacks, evaluations=t.evaluations, wall_s=t.wall_s,
                compile_s=t.compile_s, assembly_s=t.assembly_s, factorisation_s=t.factorisation_s, evaluation_s=t.evaluation_s,
                other_s=other, factorisation_each_s=t.factorisation_each_s,
                nan=not _finite(eq.x, eq.force, eq.history[: int(eq.iterations) + 1], eq.energy))


def _unsolved(reason):
    return dict(converged=False, reason=reason, iterations=0, residual_N=None, worst_node=None, factorisations=0,
                fallbacks=0, evaluations=0, wall_s=None, compile_s=None, assembly_s=None, factorisation_s=None,
                evaluation_s=None, other_s=None, factorisation_each_s=None, nan=False)


def run_case(case: RobustnessCase):
    """Build and solve ``case``: its record (a dict: case, family, nodes, dof, read (False: FEMNET's reader
    refused it), the :func:`solve_record` fields, tol, max_iter, expected (the outcome is one the case
    accepts), build_s (building the scene and its start, s), peak_MB and peak_source)."""
    import jaxnet as jn
    from jaxnet.scene import SceneError

    from validation import stability

    record = dict(case=case.name, family=case.family, nodes=None, dof=None, read=True)
    reset = reset_peak_memory()
    t0 = time.perf_counter()
    try:
        setup = case.build()
    except NotRead as error:
        record.update(_unsolved(f"{NOT_READ}: {error}"), read=False)
    except SceneError as error:
        record.update(_unsolved(f"{REFUSED}: {error}"))
    else:
        record.update(nodes=setup.scene.n_nodes, dof=setup.scene.n_dof, build_s=time.perf_counter() - t0)
        newton = newton_options(setup)
        record.update(tol=newton.tol, max_iter=newton.max_iter)
        try:
            eq = jn.solve_static(setup.scene, newton, x0=setup.x0, throw=False)
        except SceneError as error:  # refused by validation, before anything compiles
            record.update(_unsolved(f"{REFUSED}: {error}"))
        except Exception as error:  # noqa: BLE001 -- one broken case must not stop the set: recorded, named
            record.update(_unsolved(f"{ERROR}: {_first_line(error)}"))
        else:
            record.update(solve_record(eq))
    record.setdefault("build_s", time.perf_counter() - t0)
    record["peak_MB"], record["peak_source"] = peak_memory_mb(reset)
    record["expected"] = bool(stability.accepted(case, record)) if record["read"] else None
    return record


# -- records ---------------------------------------------------------------------------------------------------


def _clean(value):
    """A JSON-safe copy: numpy scalars to Python, non-finite floats to None."""
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    return value


def read_records(path):
    """The records of a JSON-lines file (a truncated last line, from a killed run, is skipped)."""
    path = pathlib.Path(path)
    if not path.exists():
        return []
    records = []
    for line in path.read_text().splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return records


def run_cases(chosen, out=None, resume=False, echo=print):
    """Run ``chosen`` cases in order, appending each record to ``out`` (JSON lines) as it ends and echoing
    its table row; with ``resume``, the cases already in ``out`` are kept and not run again. Returns every
    record of ``chosen`` (kept and new), in the cases' order."""
    kept = {}
    if out is not None:
        out = pathlib.Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        if resume:
            kept = {r["case"]: r for r in read_records(out)}
        else:
            out.write_text("")
    echo(table_header())
    records = []
    for case in chosen:
        record = kept.get(case.name)
        if record is None:
            record = run_case(case)
            if out is not None:
                with out.open("a") as f:
                    f.write(json.dumps(_clean(record)) + "\n")
        records.append(record)
        echo(table_row(record))
    return records


# -- tables ----------------------------------------------------------------------------------------------------

#: the per-case table: (header, record key or function, format)
SHORT_REASONS = {"converged": "converged", "maximum number of iterations reached": "max iterations",
                 "non-finite force or energy (NaN/inf)": "non-finite"}


def short_reason(reason, width=70):
    if reason.startswith("no step decreases the energy"):
        return "stalled"
    reason = SHORT_REASONS.get(reason, reason)
    return reason if len(reason) <= width else reason[: width - 3] + "..."


def _num(value, spec):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return format(value, spec)


COLUMNS = ("case", "nodes", "conv", "reason", "it", "fact", "wall s", "asm s", "fact s", "eval s", "other s",
           "1 fact ms", "compile s", "peak MB")


def table_header():
    return "| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS)


def row_cells(r):
    """The cells of a record's row of the per-case table (:data:`COLUMNS`), as text."""
    each = r.get("factorisation_each_s")
    reason = short_reason(r["reason"]).replace("|", "/")
    if r.get("expected") is False and r["family"] == "stability":
        reason += " (unexpected)"
    return [r["case"], _num(r["nodes"], "d"), "yes" if r["converged"] else "no", reason, str(r["iterations"]),
            str(r["factorisations"]), _num(r["wall_s"], ".2f"), _num(r["assembly_s"], ".2f"),
            _num(r["factorisation_s"], ".2f"), _num(r["evaluation_s"], ".2f"), _num(r["other_s"], ".2f"),
            _num(None if each is None else 1e3 * each, ".2f"), _num(r["compile_s"], ".2f"), _num(r["peak_MB"], ".0f")]


def table_row(r):
    return "| " + " | ".join(row_cells(r)) + " |"


def summary(records):
    """Per family (and over all): rows of the summary (dicts)."""
    rows = []
    families = [f for f in FAMILIES if any(r["family"] == f for r in records)]
    for family in families + ["all"]:
        members = [r for r in records if family in ("all", r["family"])]
        solved = [r for r in members if r["read"]]
        done = [r for r in solved if r["converged"]]
        its = [r["iterations"] for r in done]
        rows.append({
            "family": family,
            "cases": len(solved),
            "not read": len(members) - len(solved),
            "converged": len(done),
            "fraction": len(done) / len(solved) if solved else None,
            "as expected": sum(bool(r["expected"]) for r in solved),
            "median it": float(np.median(its)) if its else None,
            "max it": max(its) if its else None,
            "> 25 it": sum(i > 25 for i in its),
            "> 60 it": sum(i > 60 for i in its),
            "wall s": sum(r["wall_s"] or 0.0 for r in solved) + sum(r.get("build_s") or 0.0 for r in solved),
        })
    return rows


SUMMARY_FORMATS = {"fraction": ".3f", "median it": "g", "wall s": ".1f"}


def markdown(rows, formats=None):
    """Rows (dicts, same keys) as a Markdown table."""
    if not rows:
        return "(no rows)"
    formats = formats or {}
    columns = list(rows[0])
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        cells = []
        for c in columns:
            v = row[c]
            cells.append("-" if v is None else format(v, formats[c]) if c in formats else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary_note(records):
    sources = {r["peak_source"] for r in records if r.get("peak_source")}
    return (f"Converged cases over the cases read (FEMNET's files the reader refuses are counted under *not "
            f"read*); iteration figures over the converged cases only; *as expected*: the outcome is one the "
            f"case accepts (convergence, or for the stability suite the named stop its case explains); "
            f"wall s: building and solving. Tolerance 1e-3 N, at most {MAX_ITERATIONS} iterations. Peak "
            f"memory: {', '.join(sorted(sources)) or '-'}.")


def failures(records):
    """Rows for the cases read that did not converge."""
    return [{"case": r["case"], "nodes": r["nodes"], "reason": short_reason(r["reason"], 120),
             "iterations": r["iterations"], "residual_N": r["residual_N"],
             "expected": "yes" if r["expected"] else "no"}
            for r in records if r["read"] and not r["converged"]]


def not_read(records):
    return [{"case": r["case"], "message": r["reason"][len(NOT_READ) + 2:]} for r in records if not r["read"]]


def compare(old, new):
    """Markdown: per case (in both), converged and iterations before and after; cases in one only; both
    summaries side by side."""
    before = {r["case"]: r for r in old}
    after = {r["case"]: r for r in new}
    common = [name for name in after if name in before]
    rows = []
    for name in common:
        b, a = before[name], after[name]
        rows.append({"case": name, "nodes": a["nodes"],
                     "conv before": "yes" if b["converged"] else "no", "conv after": "yes" if a["converged"] else "no",
                     "it before": b["iterations"], "it after": a["iterations"],
                     "wall before": b["wall_s"], "wall after": a["wall_s"],
                     "change": _change(b, a)})
    text = [markdown(rows, {"wall before": ".2f", "wall after": ".2f"})]
    only_old = [n for n in before if n not in after]
    only_new = [n for n in after if n not in before]
    for label, names in (("OLD", only_old), ("NEW", only_new)):
        if names:
            more = ", ..." if len(names) > 10 else ""
            text.append(f"In {label} only ({len(names)}): " + ", ".join(names[:10]) + more)
    sb = {r["family"]: r for r in summary([before[n] for n in common])}
    sa = {r["family"]: r for r in summary([after[n] for n in common])}
    side = []
    for family in sa:
        row = {"family": family, "cases": sa[family]["cases"]}
        for key in ("fraction", "median it", "max it", "> 25 it", "> 60 it", "wall s"):
            row[f"{key} before"] = sb[family][key]
            row[f"{key} after"] = sa[family][key]
        side.append(row)
    text.append("Summary over the cases in both, before and after:\n\n" + markdown(
        side, {"fraction before": ".3f", "fraction after": ".3f", "median it before": "g", "median it after": "g",
               "wall s before": ".1f", "wall s after": ".1f"}))
    return "\n\n".join(text)


def _change(b, a):
    if not (b["read"] or a["read"]):
        return ""
    if b["read"] != a["read"]:
        return "now reads" if a["read"] else "NO LONGER READS"
    if b["converged"] != a["converged"]:
        return "now converges" if a["converged"] else "NOW FAILS"
    if b["reason"] != a["reason"]:
        return "other reason"
    return ""


# -- the report section and the command line -------------------------------------------------------------------


#: the records the report compares each run with: the quick set on the solver as it was before this set existed
#: (SuperLU factorising, revision f313c60)
BASELINE = ROOT / "validation" / "results" / "robustness_before.json"


def run(report, quick: bool) -> None:
    """The report section (``python -m validation`` interface): the set at the quick or full size; the per-case
    table goes to the output and ``validation/results/robustness.json``, the report gets the summary, the
    failures and the comparison with :data:`BASELINE` per family."""
    size = "quick" if quick else "full"
    report.text(__doc__.split("\n\n", 2)[2].split("\n\nPer case")[0])
    records = run_cases(cases(size), out=report.results / "robustness.json", echo=lambda line: print(line, flush=True))
    report.heading("Summary")
    report.text(summary_note(records))
    report.table(summary(records), formats=SUMMARY_FORMATS)
    if failures(records):
        report.table(failures(records), caption="The cases that did not converge")
    if not_read(records):
        report.table(not_read(records), caption="FEMNET's files the reader refuses")
    if BASELINE.exists():
        report.heading("Against the baseline")
        comparison = compare(read_records(BASELINE), records)
        report.text("Per family, over the cases in both runs (" + BASELINE.name + ": before this set's first solver "
                    "change):\n\n" + comparison.split("Summary over the cases in both, before and after:\n\n")[-1])


def matches(name, words):
    """Whether a case's ``name`` holds ``words`` (``--only``) as whole words, in that order and side by side:
    "readme n100" picks the README panel's cases of about 10² nodes, not those of 10³ ("n1000"); "1m/s" the
    cases at 1 m/s, not at 0.1 m/s. Empty ``words`` match every name."""
    wanted, held = words.split(), name.split()
    return any(held[k:k + len(wanted)] == wanted for k in range(len(held) - len(wanted) + 1))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", choices=SIZES, default="quick")
    parser.add_argument("--only", default="", help="run the cases whose name holds these whole words, side by "
                                                   "side (\"readme n100\": not the n1000 cases)")
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="the records, JSON lines (default %(default)s)")
    parser.add_argument("--resume", action="store_true", help="skip the cases already in --out")
    parser.add_argument("--list", action="store_true", help="print the cases' names and stop")
    parser.add_argument("--method", choices=("damped", "primal-dual"),
                        help="the static method of every case (default: the library's, or the case's own)")
    parser.add_argument("--compare", nargs="+", metavar="JSON",
                        help="OLD.json [NEW.json]: compare two runs' records (NEW default: --out) and stop")
    args = parser.parse_args(argv)
    if args.compare:
        if len(args.compare) > 2:
            parser.error("--compare takes OLD.json and optionally NEW.json")
        old, new = args.compare[0], (args.compare[1] if len(args.compare) > 1 else args.out)
        print(f"OLD: {old}\nNEW: {new}\n")
        print(compare(read_records(old), read_records(new)))
        return 0

    import jaxnet  # noqa: F401  (float64 on)

    global METHOD
    METHOD = args.method
    chosen = [c for c in cases(args.size) if matches(c.name, args.only)]
    if args.list:
        print("\n".join(f"{c.family:10s} {c.name}" for c in chosen))
        return 0
    t0 = time.perf_counter()
    print(f"Robustness set, size {args.size}{f', cases matching {args.only!r}' if args.only else ''}: "
          f"{len(chosen)} cases; records in {args.out}\n", flush=True)
    records = run_cases(chosen, out=args.out, resume=args.resume, echo=lambda line: print(line, flush=True))
    print(f"\n## Summary\n\n{summary_note(records)}\n\n{markdown(summary(records), SUMMARY_FORMATS)}")
    if failures(records):
        print(f"\n## Not converged\n\n{markdown(failures(records), {'residual_N': '.3g'})}")
    if not_read(records):
        print(f"\n## FEMNET files that do not read\n\n{markdown(not_read(records))}")
    print(f"\nTotal time of this invocation: {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    sys.exit(main())
