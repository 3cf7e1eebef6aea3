"""Shared fixtures. Tests never use global random state: seeds are explicit."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from tetherland.config import Scenario, load_scenario


@pytest.fixture(scope="session")
def slope50() -> Scenario:
    return load_scenario("slope50")


@pytest.fixture(scope="session")
def pipe60() -> Scenario:
    return load_scenario("pipe60")
