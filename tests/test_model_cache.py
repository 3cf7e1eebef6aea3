"""The per-process cache of compiled MuJoCo models (issue 25): each distinct MJCF text is
compiled once, every plant gets its own copy equal to a fresh compile, and a campaign
flown with the cache gives the records and logs of one flown without it."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from tetherland.campaign import CampaignSpec, open_store, run_campaign
from tetherland.campaign.executors import InlineExecutor
from tetherland.campaign.jobs import VOLATILE, draw_run
from tetherland.campaign.store import ResultsStore
from tetherland.config import load_scenario
from tetherland.sim import Plant
from tetherland.sim.mjcf import build_mjcf
from tetherland.sim.model_cache import MODEL_CACHE, ModelCache


def model_arrays(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    """Every array field of ``model`` (sizes, options and names included) by name."""
    arrays = {}
    for name in dir(model):
        if name.startswith("_"):
            continue
        value = getattr(model, name)
        if isinstance(value, np.ndarray):
            arrays[name] = value.copy()
    for struct in ("opt", "vis", "stat"):
        for name in dir(getattr(model, struct)):
            value = getattr(getattr(model, struct), name)
            if isinstance(value, np.ndarray | float | int) and not name.startswith("_"):
                arrays[f"{struct}.{name}"] = np.array(value)
    return arrays


def assert_same_model(a: mujoco.MjModel, b: mujoco.MjModel) -> None:
    arrays_a, arrays_b = model_arrays(a), model_arrays(b)
    assert arrays_a.keys() == arrays_b.keys()
    assert len(arrays_a) > 100  # the comparison reaches the model's arrays
    for name, value in arrays_a.items():
        np.testing.assert_array_equal(value, arrays_b[name], err_msg=name)


def uncached_plant(scenario, monkeypatch) -> Plant:
    """A plant whose model was compiled for it alone (the cache off)."""
    with monkeypatch.context() as m:
        m.setattr(MODEL_CACHE, "max_entries", 0)
        return Plant(scenario)


@pytest.fixture
def fresh_cache():
    MODEL_CACHE.clear()
    yield MODEL_CACHE
    MODEL_CACHE.clear()


def test_a_plant_gets_a_copy_equal_to_a_fresh_compile_after_another_run_changed_its_own(
    slope50, fresh_cache, monkeypatch
):
    """The first plant compiles; a run then changes its model (rotor fault, control range,
    masses, the cable engaged); the second plant of the same scenario reuses the compile
    and its model equals that of a plant built without the cache."""
    first = Plant(slope50)
    assert (fresh_cache.stats.compiled, fresh_cache.stats.reused) == (1, 0)
    first.set_rotor_efficiency([0.5, 1.0, 1.0, 1.0])
    first.engage_cable()
    first.model.actuator_ctrlrange[:] *= 3.0
    first.model.body_mass[:] *= 2.0
    second = Plant(slope50)
    assert (fresh_cache.stats.compiled, fresh_cache.stats.reused) == (1, 1)
    assert second.model is not first.model and second.data is not first.data
    uncached = uncached_plant(slope50, monkeypatch)
    assert (fresh_cache.stats.compiled, fresh_cache.stats.reused) == (2, 1)
    assert_same_model(second.model, uncached.model)
    np.testing.assert_array_equal(second.rotor_efficiency, np.ones(4))


def test_the_cached_model_is_the_fresh_compile_of_its_text_and_never_handed_out(slope50):
    cache = ModelCache(max_entries=2)
    xml = build_mjcf(slope50)
    a = cache.model(xml)
    a.body_mass[:] = 7.0  # the caller owns its copy
    b = cache.model(xml)
    assert b is not a
    assert_same_model(b, mujoco.MjModel.from_xml_string(xml))
    assert (cache.stats.compiled, cache.stats.reused) == (1, 1)


def test_every_change_that_enters_the_mjcf_compiles_a_new_model(slope50, fresh_cache, monkeypatch):
    """Keyed on the full MJCF text: a heavier vehicle, a longer cable, another slope each
    compile their own model, whose masses and geometry are theirs; the plants of perturbed
    draws (sensor noise, dropouts, a rotor fault: nothing in the MJCF) share one."""
    variants = [
        slope50,
        load_scenario("slope50", ["vehicle.mass=1.3"]),
        load_scenario("slope50", ["tether.length=1.6"]),
        load_scenario("slope50", ["surface.slope_deg=40"]),
    ]
    models = [Plant(sc).model for sc in variants]
    assert (fresh_cache.stats.compiled, len(fresh_cache)) == (len(variants), len(variants))
    for sc, model in zip(variants, models, strict=True):
        assert_same_model(model, uncached_plant(sc, monkeypatch).model)
    total = [float(m.body_subtreemass[m.body("vehicle").id]) for m in models]
    assert total[1] - total[0] == pytest.approx(1.3 - slope50.vehicle.mass, abs=1e-12)
    reused = fresh_cache.stats.reused
    draws = [draw_run(slope50, seed) for seed in (1, 2)]
    draws.append(draw_run(slope50, 3, "rotor", (1.0, 72.0)))
    assert draws[2].plant.faults.active
    for drawn in draws:
        assert drawn.plant.sensors != slope50.sensors  # the draw changed the plant
        assert_same_model(Plant(drawn.plant).model, uncached_plant(drawn.plant, monkeypatch).model)
    assert fresh_cache.stats.reused == reused + len(draws)  # the draws' MJCF is the scenario's


def test_the_cache_keeps_its_newest_entries(slope50):
    cache = ModelCache(max_entries=2)
    texts = [build_mjcf(load_scenario("slope50", [f"surface.slope_deg={s}"])) for s in (40, 45, 50)]
    for xml in texts:
        cache.model(xml)
    assert len(cache) == 2
    cache.model(texts[2])  # kept
    cache.model(texts[0])  # dropped: compiled again
    assert (cache.stats.compiled, cache.stats.reused) == (4, 1)
    with pytest.raises(ValueError, match=r"max_entries must be in \[0, 1000\]"):
        ModelCache(max_entries=-1)


def _comparable(directory) -> list[dict]:
    records = []
    for r in ResultsStore(directory).load():
        r = {k: v for k, v in r.items() if k not in ("wall_time_s", "cpu_time_s")}
        r["verdict"] = {k: v for k, v in r["verdict"].items() if k not in VOLATILE}
        records.append(r)
    return sorted(records, key=lambda r: r["run_id"])


@pytest.mark.slow
def test_a_campaign_with_the_cache_equals_one_without(tmp_path, monkeypatch, fresh_cache):
    """A tethered and a contact-free run in one worker: the tethered run engages the cable
    in its model, the contact-free run reuses the compile. Records and every logged
    array are identical to a campaign that compiles each model afresh."""
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=1,
                        seed=5)  # fmt: skip
    run_campaign(spec, open_store(spec, tmp_path / "cached"), InlineExecutor(), keep="all")
    assert fresh_cache.stats.reused >= 1  # the second run flew a copy
    monkeypatch.setattr(MODEL_CACHE, "max_entries", 0)
    MODEL_CACHE.clear()
    run_campaign(spec, open_store(spec, tmp_path / "fresh"), InlineExecutor(), keep="all")
    assert MODEL_CACHE.stats.reused == 0 and MODEL_CACHE.stats.compiled == 2
    cached, fresh = _comparable(tmp_path / "cached"), _comparable(tmp_path / "fresh")
    assert [r["run_id"] for r in cached] == ["free-flight-base-00000", "tethered-base-00000"]
    assert json.dumps(cached, sort_keys=True) == json.dumps(fresh, sort_keys=True)
    for r in cached:
        with np.load(tmp_path / "cached" / r["run_dir"] / "log.npz") as a, \
                np.load(tmp_path / "fresh" / r["run_dir"] / "log.npz") as b:  # fmt: skip
            names = [n for n in a.files if n != "__metadata__"]
            assert names == [n for n in b.files if n != "__metadata__"] and len(names) > 20
            for name in names:
                np.testing.assert_array_equal(a[name], b[name], err_msg=f"{r['run_id']} {name}")


def test_provenance_asks_git_and_the_libraries_once_per_process(slope50, monkeypatch):
    """The commit and the versions are read once (a subprocess and five metadata reads
    per run otherwise); a caller's changes to its record never reach the next one."""
    import subprocess

    from tetherland import provenance as prov

    prov._git_commit.cache_clear()
    prov._library_versions.cache_clear()
    calls = []
    real_run = subprocess.run
    monkeypatch.setattr(subprocess, "run", lambda *a, **k: calls.append(a) or real_run(*a, **k))
    first = prov.provenance(slope50, seed=1)
    first["libraries"]["numpy"] = "changed by a caller"
    second = prov.provenance(slope50, seed=2)
    assert [a[0][:3] for a in calls if a[0][0] == "git"] == [
        ["git", "--no-optional-locks", "describe"]
    ]
    assert second["git_commit"] == first["git_commit"]
    assert second["libraries"]["numpy"] == np.__version__
    assert second["seed"] == 2 and second["scenario_name"] == "slope50"
