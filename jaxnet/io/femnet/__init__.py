"""FEMNET's case files: a ``.don`` description (and FEMNET's own ``.mdg`` mesh) read into jaxnet.

FEMNET is the C program of the same netting model. Its user writes a ``.don`` file; its mesher writes
the ``.mdg`` mesh; its solver the ``.sta`` equilibrium. Two readers:

* :func:`read_don` maps a ``.don`` case onto the :class:`~jaxnet.net.Net` builder (jaxnet meshes the
  panels itself);
* :func:`read_mdg` builds a :class:`~jaxnet.scene.Scene` from FEMNET's ``.mdg`` mesh directly (same
  nodes in the same order, same triangles, same bars) with the ``.don``'s materials and node types, so
  that the physics of the two programs can be compared without mesh differences.

and one writer: :func:`write_design` writes a design of a ``.don`` case (its cuts, twines and rope lengths,
:mod:`jaxnet.design.space`) back as a ``.don`` file, a copy of the source with the design's numbers.

Conventions established from the files (see ``tests/io/test_femnet.py``):

* **Twine coordinates.** A ``.don`` corner's (U, V), and the (U, V) of a triangle corner in the
  ``.mdg``, count *meshes* along the two *diagonals* of the meshes (U along the first diagonal, V
  along the second; with a meshing step of 2 l0 FEMNET's lattice steps by 1 in both). FEMNET's mesher
  converts them to twine coordinates u = U + V, v = V - U (phobos ``chargement_don.c``), which count
  *twines* along the two twine directions; those are jaxnet's twine coordinates. Check: with
  (u, v) = (U + V, V - U), jaxnet's :func:`~jaxnet.geometry.twine_vectors` of FEMNET's equilibrium
  positions reproduce the two twine vectors per triangle of the ``.sta`` to 1e-9 m (the ``.sta``
  lists the v vector first, then the u vector), and their lengths are l0 (one twine) as they must.
  The map has determinant 2: one mesh (U = 1) is one twine of each family; d(u, v) = 2 d(U, V) and
  the number of twines of each family in a triangle is |d(u, v)|/2 = |d(U, V)|.
* **Meshing step** (m): jaxnet's mesher uses step / l0 twines, as FEMNET's (7.27 twines in
  ``nr_netting``: 0.16 m / 0.022 m).
* **Meshing by mesh diagonals** (``input Meshing_UV PANEL NU NV``: phobos ``chargement_don.c`` sets the panel's
  ``pas_U``, ``pas_V``; ``maillage.c`` then meshes a panel of meshing type 2 with ``maillage_interne4`` of
  ``maillage_panneau2.c``): the interior nodes lie on the lattice of every NU meshes along U and NV along V
  (:func:`~jaxnet.mesh.panel.mesh_panel`'s ``lattice``, ``Net.panel(lattice=(NU, NV))``, whose docstring says
  what FEMNET does and where jaxnet differs); the sides are divided as without it (by the sewn cable meshed
  first, FEMNET's advice for this command). FEMNET ignores the command for the other meshing types (a warning
  here); ``Meshing_uv`` (small uv: every nu, nv twines, ``maillage_interne6``) is another command, refused.
* **Node types.** Every node has a type (corner: its own; nodes created along a panel side: the
  side's "following type"; inside a panel or a cable: the element's "type of internal nodes").
  Fixity "Displacement X,Y,Z" = 1 holds that coordinate; "Symmetry" = 1 means the node lies on a
  symmetry plane normal to that axis, so that coordinate is held too (the plane is a mirror: the
  node's out-of-plane displacement is zero by symmetry). FEMNET reports no reaction there and zeroes
  the total force along symmetry axes; :func:`femnet_figures` does the same. A type's mass, force and box
  are the whole structure's: a node on a symmetry plane carries half of them (a quarter on two planes;
  :func:`~jaxnet.io.femnet.surroundings.symmetry_share`).
* **Links** ("Links number", phobos ``chargement_don.c``): one line per link, ``nb_pt: N`` then N
  points ``pa: k nd: c`` (corner c of diamond panel k), ``ha: k nd: c`` (hexagonal panel) or ``el: k
  nd: e`` (end e of cable k); FEMNET goes by the first letter, ``c`` and ``w`` being sliding cables and
  winches (refused here). The points of a link are one node; so are, with ``input link d``, all the
  points closer than d m (FEMNET's automatic links), and here also points at one place (jaxnet's
  :class:`~jaxnet.net.Net` joins them). The joined node starts at the mean of the points' start
  positions, as FEMNET's ``numerotation.c`` places it: the reader moves the joined corners and cable
  ends there before meshing. Sewing (``liaison_maille`` and ``maillage_contour_panneau2`` in
  ``maillage_panneau*.c``): a panel side whose two corners are joined to the two corners of another
  panel's side, or to the two ends of a cable, is sewn to it: the later-meshed part takes the number
  of nodes of the part meshed first, at the same proportions along the side, its nodes are linked to
  those, and each panel keeps its own twine coordinates there (interpolated along its own side). Here
  the sides become :meth:`~jaxnet.net.Net.seam` pairs and the cables ``Net.cable(along=side)``; the
  division of sewn sides is the cable's number of bars when a cable is meshed first ("Meshing order"),
  as FEMNET's (``nr_netting``'s one-bar cables 3, 4, 6, meshed after the panel, become 11, 16 and 16
  bars in its ``.mdg``; ``c2``'s cod line, meshed first, keeps its 7), and otherwise jaxnet's (the
  largest default division of the sewn sides; FEMNET's is the first-meshed panel's, whose side nodes
  sit where its twines cross the side: jaxnet's mesher differs from FEMNET's anyway). FEMNET does not
  sew a panel to itself; the reader refuses a panel (or cable) two of whose corners (ends) are joined,
  a point in two links, and a cable joined at both ends to a cable of several bars (FEMNET threads it
  on that cable's nodes). A joined node whose points have different node types of the same rank (two
  corners, two cable ends) takes the first met (panels before cables, in the file's order): FEMNET warns
  and keeps one; ``info["warnings"]`` says which. Points at one place that no link joins are refused
  (FEMNET keeps them apart; jaxnet's Net joins points at one place).
* **Hexagonal panels** ("hexagonal panels number"; ``chargement_don.c``): laid out as diamond panels,
  but after the corners FEMNET skips one whole line (a field written there is lost to FEMNET; refused
  here), then reads three values (twine families l, m, n) for traction stiffness (N), compression
  stiffness (N), unstretched length (m) and hydrodynamic diameter (m), then volumic mass, normal Cd,
  tangential Cd, meshing step, type of internal nodes and meshing type (1, 2: triangles; 3: twines as
  bars, refused); no opening stiffness and no knot size. Their (U, V) count *base meshes* exactly as
  jaxnet's :mod:`jaxnet.terms.hexagonal` does, so they are passed unchanged (not turned into U + V,
  V - U): FEMNET's solver (unix ``etirement_hexa.c``, ``calcul_lmn_hexa``) takes the triangle's
  vectors U = dx/dU, V = dx/dV from the corners' (U, V) (``.mdg``, read into ``lon`` by
  ``lectureDo4.c``) and puts the three neighbours of a knot at 0 (twine m), (U + V)/2 (n) and V (l),
  which are jaxnet's P_m, P_n = P_m + (U + V)/2, P_l = P_m + V (book 4.83-4.84), with forces
  (T_l - T_m, -T_n) on (U, V) as jaxnet's. jaxnet's hexagonal netting has one twine diameter and no
  drag: the diameter D with FEMNET's three's weight, D² sum l0_i = sum d_i² l0_i, and a current with
  hexagonal panels is refused. jaxnet meshes a hexagonal panel with step / (3 mean l0) base meshes.
* **Numerical twines** (``input netting2ropes PANEL PERIOD GAP_U GAP_V ACCURACY BARS``, FEMNET's meshing type 4,
  which that line sets; :mod:`.twines`): the panel is meshed as bars along its twines
  (:mod:`jaxnet.mesh.twines`), of its material scaled by PERIOD, as FEMNET's mesher and solver do, and read
  from FEMNET's ``.mdg`` too (its bars of type -PANEL). FEMNET's mesher doubles a rope meshed before such a
  panel (:mod:`.twines` says how); jaxnet's is single.
* **Added mass** acts in dynamics only (``lectureDo4.c``: "n'intervient qu'en dynamique"): each node gets its
  type's, shared over the symmetry planes as its mass is (``Nodes.added_mass``, per axis; listed per node type
  in ``info["added_mass"]``); statics leaves it out.
* **Node bodies.** A node type's **length** X,Y,Z (m) and **drag coefficient** X,Y,Z make its nodes boxes
  (``Net.body``: ``Nodes.drag_length``, ``Nodes.drag_coefficient``; :func:`jaxnet.terms.drag.box_drag`).
  FEMNET's statics (``traineecourant2.c``) drags a box along x by ½ ρ Cd_x L_y h U² cos θ and along y by
  ½ ρ Cd_y L_x h U² sin θ, h its immersed height (the box stands above its node for L_z > 0, below it for
  L_z < 0, FEMNET's "lest"), which is jaxnet's box drag for a horizontal current. FEMNET also *floats* a
  box (``flotteur2.c``: rho g L_x L_y times its immersed height, along z): a box with a volume displaces
  V = |L_x L_y L_z| (``Nodes.volume``). FEMNET's water surface is z = 0, and so is that of jaxnet's scenes
  from FEMNET (``Environment.surface_level``): a box floats by its immersed part, FEMNET's law
  (:func:`jaxnet.terms.surface.box_fraction_integral`), and is dragged by it; bars crossing the surface float
  by jaxnet's profile (:mod:`jaxnet.terms.surface`), and diamond netting stays buoyant wherever it is, as in
  FEMNET's statics (``Environment.floating``, :func:`.surroundings.environment_of` says how each compares). Gear
  drawn above z = 0 (bottom trawls drawn at z > 0 rest on a sea bed at z = -depth) starts with its bars and
  boxes in air and sinks, as in FEMNET. ``info["boxes"]`` lists the
  nodes with a box and the height of its top above them. Widths X, Y must be >= 0 (FEMNET
  takes them signed: a negative one would drag against the current).
* **Spheres** (``input sphere_element CABLE COUNT D B``; ``sphere_element2`` adds the length L they are spread
  over): COUNT spherical floats of diameter D (m) along the cable, each pulling up with B newtons net of its
  weight, Cd 0.6. FEMNET's laws fold them into the cable (``chargement_don.c``): its diameter, volumic mass and
  normal Cd become those of cable and spheres together (:func:`~.surroundings.spheres_folded`); jaxnet's make them
  floats of COUNT B newtons and drag area COUNT 0.6 pi D²/4 shared equally by the cable's nodes
  (:func:`~.surroundings.spheres`, ``Net.float``).
* **Node re-typing** (``input type_noeud_XYZ_SUPINF MODE BOUNDS... TYPE``): the nodes whose start position
  lies strictly inside FEMNET's window (modes 1-13: one bound, an interval on one, two or three axes) take
  the type. **Translations** (``input add_{x,y,z}_{ele,pan} D FIRST LAST``) move cables or panels FIRST to
  LAST by D (m) before they are meshed and joined.
* **Design plane** ("design in the plane normal to axis": 1, 2 or 3): the plane FEMNET's mesher draws a
  panel in; it permutes the coordinates to draw and writes its mesh back in the file's order, so x y z are
  world coordinates whatever the axis, and jaxnet's mesher (in 3-D) needs nothing of it
  (``info["design_plane_axis"]``).
* **Labels.** FEMNET reads a value after the next colon, whatever the text before it; its cases are written
  with long English labels, short ones (``Kt: Kc: L: Vm: D: Cd: f: Nb: Ty:``, ``Rt: Rc: Le: De: Di: Cf:``, ...)
  and French ones (``Raideur traction (N) :``, ``Seuil de convergence (N) :``, ...): every spelling found in
  the corpus is a pattern of its field in :mod:`.grammar`. A cable may be written on one line, both ends
  and its material (FEMNET's short syntax ``Ca: 1 D: 1 x y z type 2 x y z type Kt: ...``).
* **Text outputs** (``Distances number``, ``Forces number``, ``Tensions number``, ``Positions number``): the
  figures FEMNET prints after its solve (distance between two of its global nodes, force on one along an
  axis, tension of a cable at an end, position of a node), each with its comment: read into
  ``info["text_outputs"]``; :func:`text_output_figures` computes them at an equilibrium, naming nodes by
  FEMNET's global numbers (the joined points in the order of their first corner or end, as its ``.mdg`` lists
  them first: ``info["global_nodes"]``). A distance from a node to itself ("#PELAGIC TRAWL# no global 1: 1 no
  global 2: 1", always 0 m) is how FEMNET's cases print a title: it is a heading there, not a figure.
  ``output NAME ...`` commands (prints and drawings) are read and listed in ``info["outputs"]``; they change
  nothing.
* **Commands of the tail.** ``input wave_model N`` picks the waves' theory (1 Airy, 2 Stokes second order:
  :class:`jaxnet.water.waves.Stokes2`; 3 is refused); ``input speed_type_node2`` (towing speeds, its time table on
  the next lines) moves the nodes of its type in a dynamic run (:func:`.motion.towing_of`). FEMNET's winches
  (``hauling_cable4``/``6``, with their tables) change their cables' rest lengths in a dynamic run
  (:func:`.motion.winches_of`, :class:`jaxnet.water.forcing.Winch`); ``info["dynamic_only"]`` names them, left out
  of a static run; ``node_position``, which FEMNET's current
  code has no handler for, is read and ignored (``info["ignored"]``); the table of a command commented out
  is skipped with it. A drag coefficient left out of its line (``Normal Cd:`` then the next label) is
  FEMNET's unset value, 0, said in ``info["warnings"]``.
* **Sea bed** (``fond.c``). Where a node type's **limits sense** is 1 (a floor) or -1 (a ceiling) along an
  axis, its **limit** (m) along that axis is read (``Net.limit``: ``Nodes.limit``, ``Nodes.limit_sense``):
  FEMNET pushes a node beyond it back by k (limit - x), k the "stiffness of the insertion in the sea bottom"
  (N/m), which is ``Environment.bottom_stiffness``; ``bottom_band`` = 0 gives this law exactly (jaxnet's
  default band smooths the contact: :mod:`jaxnet.terms.bottom`). A sense 0 is no limit (its value is
  unused). A limit with a stiffness 0 does nothing in FEMNET and is refused. The "wearing coefficient on the
  bottom" is ``bottom_friction``: FEMNET's statics apply it only with ``input moving_bottom``, as the friction of a
  bottom sliding at the current's speed (a still bottom exerts none, ``Bottom.moving`` = 0:
  ``Environment.bottom_moving`` False), its dynamics on every node that presses on the bed, against the node's
  velocity (``fond_dyn.c``; :mod:`jaxnet.terms.bottom`). ``info["sea_bed"]`` and ``info["node_bodies"]`` say
  what was read.
* **Catch.** FEMNET's catch volume is that of the *modelled* part (``c2``, a quarter model, asks for
  and reports 0.2 m³); jaxnet's :class:`~jaxnet.scene.Catch` takes the whole cod-end's volume and the
  number of copies (2 per symmetry plane used by the nodes): volume = 0.2 × 4 for ``c2``. The axis is
  the current's direction, through the intersection of the symmetry planes. ``input catch_gravity RHO_C`` makes it
  a gravity catch (``Catch.density``, :mod:`jaxnet.terms.gravity_catch`): the axis points down, the level is solved
  for the same volume and the pressure is FEMNET's hydrostatic one; refused in a current (FEMNET then gives the
  netting no drag at all). Each ``input catch2_volume V N P1 .. PN`` is a catch of its own held by the listed
  diamond panels (:meth:`~jaxnet.net.Net.panel_catch`, :mod:`jaxnet.terms.panel_catch`), its front along x as
  FEMNET places it, its netting on FEMNET's side (the catch on the U ^ V side of every panel,
  :func:`~jaxnet.io.femnet.surroundings.femnet_panel_catch_sides`), the main catch's Cd. FEMNET's current statics give
  a case with such catches no netting drag (their loop calls neither its netting drag nor the drag ahead of the
  fronts); its stored answer of 15grid/avril_4 has it, and so has jaxnet.
* **Convergence.** FEMNET stops when the *mean* nodal residual norm is below its threshold; jaxnet's
  Newton tests the *largest* nodal residual. The threshold is passed unchanged as jaxnet's ``tol``:
  max <= tol implies mean <= tol, so jaxnet's answer is at least as converged as FEMNET's.
* **Environment.** z is up, the water density FEMNET's default 1025 kg/m³ unless ``input
  water_density`` says otherwise, g = 9.81 m/s². The current direction (deg) turns from x towards y.
  The water plane is z = 0 (a free surface, as FEMNET's statics have it: see node bodies above).

Strictness. FEMNET skips to the next colon and reads numbers, whatever the text before the colon; this
reader checks each label against the field it expects (the long and the short spellings found in
FEMNET's cases), and raises :class:`~jaxnet.scene.SceneError` naming the file, the LINE and the field
for: a misspelt label, a missing or non-numeric value (truncated file; numbers as C's scanf reads them),
NaN/inf, a negative stiffness or length (a node box's height excepted: it hangs below its node), a
zero-length cable, a panel whose (U, V) contour has no area, positions, limits and node box sizes beyond
1e5 m, meshes of more than 50000 nodes per panel or cables of more than 5000 bars (FEMNET's own limits are
20000 nodes and 5000 bars in all), a link to a part that does not exist, and every FEMNET feature it does
not model when it is used (sea-bed limits without a stiffness, hexagonal netting in a current, twines
meshed as bars (meshing type 3), sliding cables, anisotropic node mass, extra catch volumes,
FEMNET's other drag laws, meshing along the twines (``Meshing_uv``), unknown ``input`` commands, ...). Dynamic cases (an end time > 0) and waves are read: the time settings
go to ``info["dynamic"]`` (``jaxnet run CASE.don --dynamic``), the waves to ``Environment.waves`` (linear
waves on FEMNET's surface z = 0, a depth of 0 taken as deep water), the node types' added masses to the nodes
(``Nodes.added_mass``).
:func:`read_don` also builds the net it returns, so that errors of meshing and of the scene (a net held
nowhere, ...) come named with the file and a line too. "Meshing order" may be FEMNET's shorthand: a word beginning with ``a`` (cables, then panels,
then hexagonal panels) or ``b`` (panels, hexagonal panels, cables).

Modules: :mod:`.reader` (FEMNET's way of reading, strict: labels, numbers, ``file:LINE:`` errors),
:mod:`.grammar` (the ``.don``'s fields and commands as tables; :class:`DonFile`, the file as read),
:mod:`.parse` (:func:`parse_don`), :mod:`.links` (links and seams planned before meshing), :mod:`.twines`
(numerical twines), :mod:`.mapping`
(onto jaxnet's :class:`~jaxnet.net.Net`: :func:`read_don`), :mod:`.mdg` (:func:`read_mdg`), :mod:`.results`
(:func:`femnet_figures`, :func:`read_sta`).
"""

from jaxnet.io.femnet.grammar import MAX_BARS, MAX_PANEL_NODES, DonFile, twine_coordinates
from jaxnet.io.femnet.links import MERGE_TOLERANCE
from jaxnet.io.femnet.mapping import read_don, released_gauge
from jaxnet.io.femnet.surroundings import GRAVITY, WATER_DENSITY
from jaxnet.io.femnet.mdg import read_mdg
from jaxnet.io.femnet.parse import parse_don
from jaxnet.io.femnet.reader import MAX_COORDINATE, MAX_MESHES, Value
from jaxnet.io.femnet.results import (femnet_figures, global_node, printed_figure, read_sta, read_sta_summary, sta_positions,
                                      started_from_sta,
                                      text_output_figures)
from jaxnet.io.femnet.writer import write_design

__all__ = ["GRAVITY", "MAX_BARS", "MAX_COORDINATE", "MAX_MESHES", "MAX_PANEL_NODES", "MERGE_TOLERANCE", "WATER_DENSITY",
           "DonFile", "Value", "femnet_figures", "global_node", "parse_don", "printed_figure", "read_don", "read_mdg", "read_sta",
           "released_gauge",
           "read_sta_summary", "sta_positions", "started_from_sta", "text_output_figures",
           "twine_coordinates", "write_design"]
