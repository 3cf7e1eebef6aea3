"""Judging runs: one function for every landing method, from the run's files alone.

* :mod:`.record`: :class:`RunRecord` (``run.json``), what a method reports besides the log;
* :mod:`.judge`: :func:`judge`, touchdown, crash, slip and conditions (1)-(5) on the plant's
  truth, with an :class:`Outcome` and the ``summary.json`` document.
"""

from tetherland.verdict.judge import Outcome, Verdict, judge, not_flown, tolerances_of
from tetherland.verdict.record import (
    RECORD_FILE,
    Expectations,
    PhaseSpan,
    RunRecord,
    RunRecordError,
    SwitchSpan,
)

__all__ = [
    "RECORD_FILE",
    "Expectations",
    "Outcome",
    "PhaseSpan",
    "RunRecord",
    "RunRecordError",
    "SwitchSpan",
    "Verdict",
    "judge",
    "not_flown",
    "tolerances_of",
]
