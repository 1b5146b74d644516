"""What moves in a FEMNET case's run in time: towed node types (:func:`towing_of`), winches hauling or paying
out cables (:func:`winches_of`), and the case's time settings (:func:`time_settings`: its end, time step, records
and loading). The conventions are the package's docstring's (:mod:`jaxnet.io.femnet`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.case import TimeSettings
from jaxnet.io.femnet.grammar import DonFile
from jaxnet.scene import SceneError
from jaxnet.solve.options import TIME_STEP, Implicit, Newton


TOWING = "speed_type_node2"


def towing_of(case: DonFile, node_type) -> tuple:
    """The prescribed motions of FEMNET's ``input speed_type_node2 TYPE K`` and its table (times, then the speeds
    along x, y and z at them): the nodes of TYPE moved by a :class:`jaxnet.water.forcing.SpeedTable`, as FEMNET's
    ``dyna`` moves them (``mvb``: the interpolated speed within the table's times, standing still outside). A
    case without it, or read without node types, has none. FEMNET holds the towed coordinates while it moves
    them; jaxnet holds its prescribed nodes throughout, so the type must hold them on every axis: a
    SceneError naming the line says so otherwise."""
    from jaxnet.water import forcing

    if TOWING not in case.inputs or node_type is None:
        return ()
    line = case.inputs[TOWING]
    values = np.asarray(line.value, dtype=float)
    t, k = int(values[0]), int(values[1])
    table = values[2:].reshape(4, k)
    if t not in case.types:
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': node type {t} is not described")
    if not all(bool(f.value) for f in case.types[t].fixed):
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': the nodes of type {t} are towed but not held on "
                         "every axis (its 'Displacement X,Y,Z' 1 1 1): jaxnet moves only held nodes")
    nodes = np.array([i for i, typ in enumerate(node_type) if typ == t], dtype=np.int64)
    if nodes.size == 0:
        return ()
    try:
        table_motion = forcing.SpeedTable(table[0], table[1:].T)
    except ValueError as err:
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': {err}") from None
    return (forcing.PrescribedMotion(nodes, table_motion),)


WINCHES = ("hauling_cable4", "hauling_cable6")


def cable_in_order(case: DonFile, scene, k: int, where: str) -> np.ndarray:
    """The bar indices of FEMNET's cable ``k`` (0-based) in the scene, in their order from its extremity 1 to its
    extremity 2 (the chain of its bars walked from the end nearest the .don's extremity 1). SceneError, naming
    ``where``, for a cable whose bars do not make one open chain."""
    bars = np.asarray(scene.bars.cable) if scene.bars is not None else np.zeros(0, dtype=int)
    mine = np.flatnonzero(bars == k)
    if mine.size == 0:
        raise SceneError(f"{where}: cable {k + 1} has no bars in the scene")
    ends = np.asarray(scene.bars.ends)[mine]
    touching = {}
    for b, (i, j) in enumerate(ends.tolist()):
        touching.setdefault(i, []).append(b)
        touching.setdefault(j, []).append(b)
    tips = [n for n, at in touching.items() if len(at) == 1]
    if len(tips) != 2 or any(len(at) > 2 for at in touching.values()):
        raise SceneError(f"{where}: the bars of cable {k + 1} do not make one open chain: a winch needs its ends")
    position = np.asarray(scene.nodes.position)
    start = min(tips, key=lambda n: float(np.linalg.norm(position[n] - case.cables[k].ends[0])))
    order, node, seen = [], start, set()
    while True:
        step = [b for b in touching[node] if b not in seen]
        if not step:
            break
        b = step[0]
        seen.add(b)
        order.append(int(mine[b]))
        i, j = ends[b]
        node = j if i == node else i
    if len(order) != mine.size:
        raise SceneError(f"{where}: the bars of cable {k + 1} do not make one open chain: a winch needs its ends")
    return np.array(order, dtype=np.int64)


def winches_of(case: DonFile, scene, warnings: list) -> tuple:
    """The winches (:class:`jaxnet.water.forcing.Winch`) of FEMNET's ``input hauling_cable4 CABLE MIN MAX K`` and its
    table (the times, the hauling speeds in m/s, > 0 hauling in, < 0 paying out, the extremity hauled from), as
    FEMNET's ``dyna`` applies them (``hauling_cable``/``find_bar``): hauling in shortens the cable's bars from the
    extremity given, each down to MIN; paying out lengthens them from the other extremity, each up to MAX (the
    drum is at the extremity given). The drum's bar is the one at that extremity. A table whose speed changes
    sign, or whose extremity changes, is refused naming its line (FEMNET then changes the bar it starts from;
    jaxnet's winch takes its bars in one order). ``hauling_cable6`` (in the corpus, not in FEMNET's manual) is
    read as ``hauling_cable4``, which has the same line, with a warning."""
    from jaxnet.water import forcing

    out = []
    for name, values, line in case.commands:
        if name not in WINCHES:
            continue
        where = f"{case.path}:{line}: 'input {name}'"
        values = np.asarray(values, dtype=float)
        cable, k = int(values[0]), int(values[3])
        shortest, longest = values[1], values[2]
        times, speeds, extremity = values[4:].reshape(3, k)
        if not 1 <= cable <= len(case.cables):
            raise SceneError(f"{where}: cable {cable} is not described (the case has {len(case.cables)})")
        used = extremity[:-1] if k > 1 else extremity
        if not (set(used.tolist()) <= {1.0, 2.0}) or len(set(used.tolist())) != 1:
            raise SceneError(f"{where}: the extremity hauled from must be 1 or 2, the same in every row but the "
                             f"last (jaxnet's winch takes its bars in one order), got {extremity.tolist()}")
        if (speeds > 0).any() and (speeds < 0).any():
            raise SceneError(f"{where}: the speeds must all haul in (>= 0) or all pay out (<= 0), got "
                             f"{speeds.tolist()} (jaxnet's winch takes its bars in one order)")
        order = cable_in_order(case, scene, cable - 1, where)
        at_drum = order if extremity[0] == 1.0 else order[::-1]
        paying_out = (speeds < 0).any()
        try:
            winch = forcing.Winch(at_drum[::-1] if paying_out else at_drum, drum_bar=int(at_drum[0]), times=times,
                                  speeds=speeds, shortest=shortest, longest=longest)
        except ValueError as err:
            raise SceneError(f"{where}: {err}") from None
        if name == "hauling_cable6":
            warnings.append(f"{where}: not in FEMNET's manual; read as 'input hauling_cable4', which has the same line")
        out.append(winch)
    return tuple(out)


def time_settings(case: DonFile, solver: Newton, node_type=None, scene=None, warnings=None) -> TimeSettings | None:
    """FEMNET's dynamic settings as a run in time, None for a static case (end time 0): to the end of its
    records, a record every "record time step", steps of its "time step", each step's Newton the time steps'
    own (:data:`jaxnet.solve.options.TIME_STEP`) with the case's threshold, iterations and displacement limit
    (``solver``, FEMNET's numerics: its dynamics iterates each step to the same criterion). FEMNET's
    "beginning time of record" is kept in ``info`` only: jaxnet records from the start. Its towing speeds
    (:func:`towing_of`, given the scene's ``node_type``) are the loading's motions, its winches
    (:func:`winches_of`, given the ``scene``; their warnings appended to ``warnings``) the loading's winches."""
    n = case.numeric
    if not n["record_end"].value > 0:
        return None
    from jaxnet.water.forcing import Loading

    newton = dataclasses.replace(TIME_STEP, tol=solver.tol, max_iter=solver.max_iter, max_step=solver.max_step)
    return TimeSettings(end_time=n["record_end"].value, record_every=n["record_dt"].value,
                        solver=Implicit(time_step=n["dt"].value, newton=newton),
                        loading=Loading(motions=towing_of(case, node_type),
                                        winches=() if scene is None else winches_of(
                                            case, scene, [] if warnings is None else warnings)))
