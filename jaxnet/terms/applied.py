"""Forces applied to nodes: a constant external force (N) on each node, given by the user (FEMNET's node
types' "External forces X,Y,Z"), e.g. the pull of a towing warp or a weight hung from a rope end.

A load: independent of the positions, evaluated once per solve, no stiffness.
"""

from __future__ import annotations

from jaxnet.terms.term import EXTERNAL, LOAD, Term, any_nonzero, register


def node_force(force):
    """The (1, 3) force (N) on one node: its ``Nodes.force``."""
    return force[None, :]


NODE_FORCE = register(Term(
    name="node_force", family="nodes", kind=LOAD, element=node_force, arguments=lambda p, env: {"force": p.force},
    active=lambda scene, dynamic: {} if any_nonzero(scene.nodes.force) else None, group=EXTERNAL))
