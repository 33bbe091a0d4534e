"""The compiled views of the step's named tuples (formation_env.sim.views): the same fields, shared not copied,
nested named tuples viewed in turn, and the views the decision kernels receive."""

from typing import NamedTuple

import numba as nb
import numpy as np

from formation_env.sim import EnvConfig, Simulation
from formation_env.sim.dispatch import pack_structs
from formation_env.sim.views import StructView, struct_view, view_type


class Inner(NamedTuple):
    table: np.ndarray
    scale: float


class Outer(NamedTuple):
    values: np.ndarray
    count: int
    inner: Inner


@nb.njit
def _read_through_view(t, k):
    v = struct_view(t)
    v.values[k] += 1.0  # writes the NumPy array itself
    return v.values[k] * v.inner.scale + v.inner.table[k, 1] + v.count


@nb.njit
def _read_through_tuple(t, k):
    return t.values[k] * t.inner.scale + t.inner.table[k, 1] + t.count


def test_a_view_reads_and_writes_the_named_tuples_own_fields():
    rng = np.random.default_rng(0)
    t = Outer(values=rng.normal(size=5), count=3, inner=Inner(table=rng.normal(size=(5, 2)), scale=0.7))
    before = t.values.copy()
    got = _read_through_view(t, 2)
    assert t.values[2] == before[2] + 1.0  # shared, not copied
    assert got == _read_through_tuple(t, 2)  # the same arithmetic, bit for bit


def test_nested_named_tuples_are_views_too():
    t = Outer(values=np.zeros(2), count=1, inner=Inner(table=np.zeros((2, 2)), scale=1.0))
    typ = nb.typeof(t)
    view = view_type(typ)
    assert isinstance(view, StructView)
    fields = view.field_dict
    assert isinstance(fields["inner"], StructView) and fields["values"] == typ.types[0]
    assert fields["inner"].field_dict["scale"] == nb.float64


def test_the_decision_kernels_receive_views_of_params_state_and_output():
    sim = Simulation(EnvConfig(scenario="formation_keeping"), batch_size=1)
    packed = nb.typeof(pack_structs(sim.params, sim.state, sim.output))
    fields = packed.field_dict
    assert set(fields) == {"p", "s", "o"}
    assert all(isinstance(fields[k], StructView) for k in fields)
    assert isinstance(fields["p"].field_dict["wake"], StructView)
