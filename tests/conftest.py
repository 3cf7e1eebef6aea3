"""Shared fixtures. Tests never use global random state: seeds are explicit."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from tetherland.config import Scenario, load_scenario


def pytest_report_header(config: pytest.Config) -> str:
    """Say whether the bit-for-bit comparisons run as such (``tests/rounding.py``)."""
    from rounding import BLAS_AS_KERNELS

    how = ("bit for bit" if BLAS_AS_KERNELS else
           "to their rounding (numpy's BLAS sums dot products in another order here)")
    return f"tetherland: scalar and compiled forms compared with numpy {how}"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Modules with tests marked ``slow`` run first (each module kept together, so its
    module-scoped fixtures are built once): with ``-n 2`` the long closed-loop tests no
    longer start last on one worker while the other is idle. Order only: no test is
    skipped or changed."""
    slow_modules = {item.module for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.module not in slow_modules)


@pytest.fixture(scope="session")
def slope50() -> Scenario:
    return load_scenario("slope50")


@pytest.fixture(scope="session")
def pipe60() -> Scenario:
    return load_scenario("pipe60")
