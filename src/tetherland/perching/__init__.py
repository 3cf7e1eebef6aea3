"""The contact-free perching baseline's reference source (chapter section 6.4.1).

* :mod:`.reference`: :class:`PerchingReference`, hover, maneuver, motors off at touchdown.

The planner is :mod:`tetherland.planning.perching`; the method that plans and flies it is
:class:`tetherland.methods.ContactFreeMethod`, judged like every method by
:func:`tetherland.verdict.judge`.
"""

from tetherland.perching.reference import LanderGeometry, PerchingReference, PerchPhase

__all__ = ["LanderGeometry", "PerchPhase", "PerchingReference"]
