"""fast_init: the frozen records keep the dataclass's behaviour with a cheaper __init__."""

from __future__ import annotations

import dataclasses
import inspect
import pickle
from dataclasses import dataclass, field

import numpy as np
import pytest

from tetherland.interfaces import Command, Reference, StateEstimate
from tetherland.records import fast_init
from tetherland.state import LinkState, RigidBodyState


def _record_classes():
    """Two identical frozen slotted dataclasses, the second with fast_init."""

    def make():
        @dataclass(frozen=True, slots=True)
        class Record:
            a: float
            b: np.ndarray
            c: int = 3
            d: list = field(default_factory=list)
            e: str | None = None

        return Record

    return make(), fast_init(make())


def test_fast_init_builds_what_the_dataclass_init_builds() -> None:
    plain, fast = _record_classes()
    b = np.arange(3.0)
    for args, kwargs in (((1.0, b), {}), ((1.0, b, 7), {"e": "x"}), ((), {"a": 2.0, "b": b})):
        want, got = plain(*args, **kwargs), fast(*args, **kwargs)
        for f in dataclasses.fields(plain):
            assert getattr(got, f.name) is getattr(want, f.name) or (
                getattr(got, f.name) == getattr(want, f.name)
            )
    # the default factory runs per instance, as the dataclass's
    one, two = fast(1.0, b), fast(1.0, b)
    assert one.d == [] and one.d is not two.d
    assert inspect.signature(fast).parameters.keys() == inspect.signature(plain).parameters.keys()
    with pytest.raises(TypeError):
        fast(1.0)  # b is required
    with pytest.raises(TypeError):
        fast(1.0, b, 3, [], None, 9)  # one argument too many


def test_fast_init_records_stay_frozen_dataclasses() -> None:
    body = RigidBodyState(np.zeros(3), np.ones(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    est = StateEstimate(0.5, body, link=LinkState(0.1, 0.2), tension=3.0)
    ref = Reference(1.0, p_W=np.zeros((2, 3)), yaw=0.3)
    for record in (body, est, ref, Command(np.ones(4), 9.0)):
        first = dataclasses.fields(record)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(record, first, None)
    # every field holds what was passed or its default
    assert est.t == 0.5 and est.body is body and est.tension == 3.0 and est.gyro_bias_B is None
    assert ref.yaw == 0.3 and ref.thrust_scale == 1.0 and ref.output is None
    assert Command(np.ones(4)).diagnostics == {}
    moved = dataclasses.replace(ref, yaw=1.0)
    assert moved.yaw == 1.0 and moved.p_W is ref.p_W and moved.t == ref.t
    again = pickle.loads(pickle.dumps(LinkState(0.1, 0.2, 0.3, 0.4)))
    assert again == LinkState(0.1, 0.2, 0.3, 0.4)


def test_fast_init_refuses_what_it_cannot_reproduce() -> None:
    @dataclass(frozen=True)
    class NoSlots:
        a: float

    @dataclass(slots=True)
    class NotFrozen:
        a: float

    @dataclass(frozen=True, slots=True)
    class PostInit:
        a: float

        def __post_init__(self) -> None:
            pass

    @dataclass(frozen=True, slots=True)
    class KeywordOnly:
        a: float = field(kw_only=True)

    for cls in (NoSlots, NotFrozen, PostInit, KeywordOnly):
        with pytest.raises(TypeError):
            fast_init(cls)
