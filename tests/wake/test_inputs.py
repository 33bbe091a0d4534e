"""Bad input meets a clear ValueError naming the field."""

import math

import numpy as np
import pytest

from formation_env.geometry import LiftingSurface, Vehicle, verification_wing
from formation_env.wake import FormationState, WakeModel


@pytest.mark.parametrize("field,value", [
    ("span_m", 0.0), ("span_m", -1.0), ("aspect_ratio", 0.0), ("aspect_ratio", -2.0), ("taper", -0.1),
    ("nseg", 0), ("nseg", 2.5), ("sweep_rad", math.radians(90.0)), ("sweep_rad", -math.radians(95.0)),
    ("span_m", float("nan")), ("aspect_ratio", float("inf")), ("dihedral_rad", float("nan")),
    ("spacing", "random"), ("position_m", (0.0, float("nan"), 0.0)),
])
def test_invalid_surface_raises_naming_the_field(field, value):
    kwargs = dict(span_m=1.0, aspect_ratio=6.0)
    kwargs[field] = value
    with pytest.raises(ValueError, match=field):
        LiftingSurface(**kwargs)


@pytest.mark.parametrize("field,value", [
    ("airspeed_mps", 0.0), ("airspeed_mps", -5.0), ("airspeed_mps", np.nan),
    ("alpha_rad", np.inf), ("beta_rad", np.nan), ("euler_rad", np.nan), ("position_ned", np.inf),
])
def test_invalid_state_raises_naming_the_field(field, value):
    kwargs = dict(position_ned=np.zeros((2, 3)), euler_rad=np.zeros((2, 3)), airspeed_mps=25.0, alpha_rad=0.05, beta_rad=0.0)
    arr = np.array(kwargs[field], dtype=float, copy=True)
    arr.flat[0] = value
    kwargs[field] = arr
    with pytest.raises(ValueError, match=field):
        FormationState(**kwargs)


def test_shape_and_option_errors():
    with pytest.raises(ValueError, match="position_ned"):
        FormationState(np.zeros((2, 4)), np.zeros((2, 3)), 25.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="euler_rad"):
        FormationState(np.zeros((2, 3)), np.zeros((3, 3)), 25.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="core"):
        WakeModel([verification_wing()], core="rankine")
    with pytest.raises(ValueError, match="eval_points"):
        WakeModel([verification_wing()], eval_points="trailing_edge")
    with pytest.raises(ValueError, match="rotational"):
        WakeModel([verification_wing()], rotational="curl")
    with pytest.raises(ValueError, match="vehicles"):
        WakeModel([])
    with pytest.raises(ValueError, match="surfaces"):
        Vehicle(())
    model = WakeModel([verification_wing(), verification_wing()])
    with pytest.raises(ValueError, match="vehicles"):
        model.evaluate(FormationState(np.zeros((3, 3)), np.zeros((3, 3)), 25.0, 0.0, 0.0))
