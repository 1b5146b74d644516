"""The rigid net panel of validation/experiments.py: jaxnet's held panel (every node fixed, the reaction on the
fixed nodes read back as drag and lift) against closed forms, and against the measured drag of Patursson et al.
(2010), Ocean Engineering 37, 314-324: Cd = 0.258 at normal incidence (1 m x 1 m rigid panel, solidity 0.20,
twine 2.8 mm, bar 29 mm, U = 0.5 m/s).
"""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

from jaxnet.net import Twine
from jaxnet.terms import screen
from validation import experiments as ex

PANEL = ex.PATURSSON_2010
#: Patursson et al. (2010), measured Cd at inflow angle 0 (typed here, so that a wrong constant in the module fails)
MEASURED_CD_0 = 0.258
#: the twine's diameter, and the hydrodynamic diameter that gives the stated solidity 0.20 on 29 mm bars
TWINE_D, STATED_D = 2.8e-3, 0.20 * 0.029 / 2


def twine(diameter=TWINE_D, **kw):
    return Twine(l0=PANEL.bar, ea=1e5, diameter=diameter, density=PANEL.water_density, **kw)


def test_morison_drag_at_normal_incidence_is_the_twines_projected_area():
    """0°: every twine is normal to the current, so the drag is 1/2 rho U² Cd_n x (total twine length x d):
    two families of (side / l)² twines of length l each, i.e. 2 side² / l = 68.97 m of twine."""
    cd_n = 1.2
    _, cl, info = ex.panel_coefficients(PANEL, 0.0, twine(cd_normal=cd_n))
    total_length = 2 * PANEL.side**2 / PANEL.bar
    expected = 0.5 * PANEL.water_density * PANEL.speed**2 * cd_n * total_length * TWINE_D
    reaction = info["reaction_N"]
    assert info["converged"] and info["iterations"] == 0  # a held panel: nothing to solve
    assert -reaction[0] == pytest.approx(expected, rel=1e-10)  # 28.97 N
    assert np.abs(reaction[1:]).max() < 1e-12 * expected and abs(cl) < 1e-12


@pytest.mark.parametrize("degrees", [30.0, 60.0, 90.0])
def test_morison_angle_dependence_and_the_edge_on_limit(degrees):
    """Bars horizontal and vertical, panel turned about the vertical: the vertical twines stay normal to the
    current, the horizontal ones see it at theta. A large f (0.3) makes the tangential part visible."""
    cd_n, f = 1.0, 0.3
    theta = math.radians(degrees)
    cd, cl, _ = ex.panel_coefficients(PANEL, theta, twine(cd_normal=cd_n, tangential_ratio=f))
    cd_ref, cl_ref = ex.morison_closed_form(theta, TWINE_D, PANEL.bar, cd_n, f)
    assert cd == pytest.approx(cd_ref, rel=1e-10) and cl == pytest.approx(cl_ref, rel=1e-9, abs=1e-14)
    if degrees == 90.0:
        # edge-on, the drag is not tangential only: the vertical twines keep their full normal drag, the
        # horizontal ones (along the current) give f times theirs; no lift
        assert cd == pytest.approx(TWINE_D / PANEL.bar * cd_n * (1 + f), rel=1e-10)
        assert abs(cl) < 1e-14


def test_screen_models_edge_on():
    """theta = 90°: Løland's fit keeps only its friction constant 0.04; K&F's Fourier series vanishes; no lift."""
    cd, cl, _ = ex.panel_coefficients(PANEL, math.pi / 2, twine(drag_model="loland"))
    assert cd == pytest.approx(0.04, abs=1e-12) and abs(cl) < 1e-12
    cd, cl, _ = ex.panel_coefficients(PANEL, math.pi / 2, twine(drag_model="kristiansen-faltinsen"))
    assert abs(cd) < 1e-12 and abs(cl) < 1e-12


def test_the_panel_solidity_jaxnet_sees():
    """jaxnet's screen solidity of every element is 2 D / l: 0.193 with the 2.8 mm twine (3.6% below the
    stated 0.20), exactly 0.20 with D = 2.9 mm."""
    for diameter, sn in ((TWINE_D, 2 * 2.8 / 29), (STATED_D, 0.20)):
        net, _ = ex.panel_net(PANEL, 0.3, twine(diameter))
        scene = net.build()
        netting = scene.netting
        x = np.asarray(scene.nodes.position)[np.asarray(netting.vertices)]
        per_element = jax.vmap(screen.solidity)(x, netting.uv, netting.l0, netting.diameter)
        np.testing.assert_allclose(np.asarray(per_element), sn, rtol=1e-12)
    assert ex.solidity_diameter(PANEL.solidity, PANEL.bar) == pytest.approx(STATED_D, rel=1e-15)


@pytest.mark.parametrize("model", ["loland", "kristiansen-faltinsen"])
@pytest.mark.parametrize("diameter", [STATED_D, TWINE_D])
def test_screen_models_against_the_measured_drag(model, diameter):
    """Within 10% of the measured 0.258 at 0°. No accuracy of either fit is stated in a source we could cite;
    10% is twice the change that the panel's own solidity ambiguity (0.193 from the twines, 0.200 stated)
    makes in these models' Cd (5.9% Løland, 4.8% K&F), the part of the error the panel's description
    leaves open."""
    cd, _, _ = ex.panel_coefficients(PANEL, 0.0, twine(diameter, drag_model=model))
    assert abs(cd / MEASURED_CD_0 - 1) < 0.10


def test_morison_with_a_smooth_cylinder_misses_by_the_blockage():
    """The Morison panel with Cd_n of a smooth cylinder at the twine's Reynolds number (Re = 1333, Cd = 0.966)
    falls > 15% short of the measurement; the measured / modelled ratio is the acceleration of the water
    through the openings, (2 - Sn) / (2 (1 - Sn)²) = 1.41 at Sn = 0.20 (Bernoulli), within 10%."""
    cd_n = float(screen.cylinder_drag_coefficient(PANEL.speed * TWINE_D / ex.KINEMATIC_VISCOSITY))
    assert 0.9 < cd_n < 1.05  # the smooth-cylinder plateau at Re ~ 1e3
    cd, _, _ = ex.panel_coefficients(PANEL, 0.0, twine(STATED_D, cd_normal=cd_n))
    assert cd / MEASURED_CD_0 < 0.85
    blockage = (2 - 0.20) / (2 * (1 - 0.20) ** 2)
    assert MEASURED_CD_0 / cd == pytest.approx(blockage, rel=0.10)
