"""The one trajectory CSV codec: exact round trips for both trajectory kinds, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.planning import ManeuverSpec, ShootingTrajectory, codec, trajectory_from_csv
from tetherland.planning.perching import (
    FreeFlightMeta,
    FreeFlightTrajectory,
    PerchSpec,
    free_flight_trajectory_from_csv,
)
from tetherland.planning.perching.trajectory import SCHEMA as FREE_FLIGHT
from tetherland.planning.planner import trajectory_meta
from tetherland.planning.trajectory import OCP_SCHEMA, SPLINE_SCHEMA

SCHEMA = codec.CsvSchema("test", ("t", "a", "b"))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(5)


def test_round_trip_is_exact(rng):
    data = rng.normal(size=(7, 3)) * 10.0 ** rng.integers(-12, 12, size=(7, 3))
    meta = {"mass": 1.234567890123, "list": [1, 2.5], "name": "x"}
    text = codec.encode(SCHEMA, data, meta, scenario="s", maneuver="m", version="9")
    doc = codec.decode(text, [SCHEMA])
    np.testing.assert_array_equal(doc.data, data)  # .17g: every float comes back bit-exact
    assert doc.meta == meta and doc.kind == "test"
    assert doc.header["scenario"] == "s" and doc.header["maneuver"] == "m"
    np.testing.assert_array_equal(doc.column("b"), data[:, 2])


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda t: t.replace("# format: 1", "# format: 2"), "format"),
        (lambda t: t.replace("# kind: test", "# kind: other"), "kind 'other'"),
        (lambda t: t.replace("t,a,b", "t,a,c"), "column header"),
        (lambda t: t.replace('# meta: {"k": 1}', "# meta: {k"), "meta"),
        (lambda t: t + "1,2\n", "bad data row|values for"),
    ],
)
def test_bad_files_are_one_line_config_errors(edit, match):
    text = codec.encode(SCHEMA, np.ones((2, 3)), {"k": 1}, scenario="s", maneuver="m", version="v")
    with pytest.raises(ConfigError, match=match) as err:
        codec.decode(edit(text), [SCHEMA])
    assert "\n" not in str(err.value)


def test_shooting_trajectory_round_trip_through_the_codec(rng):
    """A tethered trajectory (hover start, random thrust accelerations) survives its file."""
    sc = load_scenario("slope50")
    spec = ManeuverSpec.from_scenario(sc)
    times = np.linspace(0.0, 1.0, 11)
    U = spec.params.G @ rng.normal(scale=0.2, size=(2, 10))
    traj = ShootingTrajectory.simulate(trajectory_meta(sc, spec), times, spec.x_start, U.T)
    doc = codec.decode(traj.to_csv(), [OCP_SCHEMA, SPLINE_SCHEMA])
    assert doc.kind == "ocp" and doc.data.shape == (11, len(OCP_SCHEMA.columns))
    again = trajectory_from_csv(traj.to_csv())
    t = rng.uniform(-0.1, 1.1, 40)
    np.testing.assert_allclose(again.sample(t).phi, traj.sample(t).phi, rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(again.U, traj.U)


def test_free_flight_trajectory_round_trip_through_the_codec(rng):
    spec = PerchSpec.from_scenario(load_scenario("slope50", ["surface.slope_deg=20"]))
    times = np.linspace(0.0, 1.5, 16)
    U = rng.normal(scale=1.0, size=(15, 2))
    traj = FreeFlightTrajectory.simulate(FreeFlightMeta.from_spec(spec), times, spec.x_start, U)
    doc = codec.decode(traj.to_csv(), [FREE_FLIGHT])
    assert doc.kind == "free-flight" and doc.header["maneuver"] == "perching"
    again = free_flight_trajectory_from_csv(traj.to_csv())
    t = rng.uniform(-0.1, 1.6, 40)
    np.testing.assert_allclose(again.sample(t).p_W, traj.sample(t).p_W, rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(again.U, traj.U)
    # one reader does not take the other kind's files
    with pytest.raises(ConfigError, match="kind"):
        trajectory_from_csv(traj.to_csv())
