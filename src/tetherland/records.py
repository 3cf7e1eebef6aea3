"""Cheaper construction of the frozen records built at the control rate.

A frozen dataclass sets each field in its ``__init__`` with ``object.__setattr__(self,
name, value)``: a generic attribute store that looks the name up on the type every time.
The records of the closed loop (:class:`~tetherland.state.RigidBodyState`,
:class:`~tetherland.interfaces.StateEstimate`, :class:`~tetherland.interfaces.Reference`,
...) are built several times per control tick, so :func:`fast_init` gives a frozen,
slotted dataclass an ``__init__`` that stores each field through its slot's own member
descriptor instead (``descriptor.__set__(self, value)``, the slot's C setter): about 40 %
fewer instructions per record. Everything else stays the dataclass's own: the signature,
the defaults and default factories, ``dataclasses.fields`` and ``replace``, equality,
``repr``, pickling, and the instance stays frozen (an assignment still raises
``dataclasses.FrozenInstanceError``).
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

T = TypeVar("T")

_MISSING = object()
"""Default of a parameter whose field has a default factory (called when it is missing)."""


def fast_init(cls: type[T]) -> type[T]:
    """Replace the ``__init__`` of the frozen, slotted dataclass ``cls`` by one that sets
    the slots through their member descriptors (same signature and defaults).

    Parameters
    ----------
    cls : type
        A ``@dataclass(frozen=True, slots=True)`` class without ``__post_init__``,
        ``init=False`` or keyword-only fields.

    Returns
    -------
    type
        ``cls`` itself, its ``__init__`` replaced.

    Raises
    ------
    TypeError
        If ``cls`` is not such a dataclass.
    """
    params = getattr(cls, "__dataclass_params__", None)
    if params is None or not params.frozen or "__slots__" not in cls.__dict__:
        raise TypeError(f"{cls.__name__} is not a frozen, slotted dataclass")
    if hasattr(cls, "__post_init__"):
        raise TypeError(f"{cls.__name__} has a __post_init__ (not supported)")
    fields = dataclasses.fields(cls)
    if any(not f.init or f.kw_only for f in fields):
        raise TypeError(f"{cls.__name__} has init=False or keyword-only fields (not supported)")
    env: dict[str, Any] = {"_MISSING": _MISSING}
    args, body = [], []
    for f in fields:
        setter = f"_set_{f.name}"
        env[setter] = cls.__dict__[f.name].__set__  # the slot's member descriptor
        if f.default is not dataclasses.MISSING:
            env[f"_default_{f.name}"] = f.default
            args.append(f"{f.name}=_default_{f.name}")
        elif f.default_factory is not dataclasses.MISSING:
            env[f"_factory_{f.name}"] = f.default_factory
            args.append(f"{f.name}=_MISSING")
            body.append(f"    if {f.name} is _MISSING:\n        {f.name} = _factory_{f.name}()")
        else:
            args.append(f.name)
        body.append(f"    {setter}(self, {f.name})")
    source = (
        f"def __make__({', '.join(env)}):\n"
        f"  def __init__(self, {', '.join(args)}):\n"
        + "\n".join("  " + line for line in "\n".join(body).splitlines())
        + "\n  return __init__\n"
    )
    namespace: dict[str, Any] = {}
    exec(source, {}, namespace)  # the source is built above from the field names
    init = namespace["__make__"](**env)
    original = cls.__init__
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__module__ = cls.__module__
    init.__annotations__ = dict(original.__annotations__)
    init.__doc__ = original.__doc__
    cls.__init__ = init  # type: ignore[misc]
    return cls


__all__ = ["fast_init"]
