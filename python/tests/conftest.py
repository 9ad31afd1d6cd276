"""Shared test helpers: the repository's fixtures and the golden reports."""

from __future__ import annotations

import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"


def fixture(name: str) -> pathlib.Path:
    """A file of `fixtures/`; a missing one fails the test (the tests are hermetic)."""
    path = FIXTURES / name
    if not path.exists():
        pytest.fail(f"missing fixture {path}")
    return path


def golden(name: str) -> dict:
    """A golden report of `fixtures/reports/` (volatile members masked)."""
    return json.loads(fixture(f"reports/{name}.json").read_text())


def assert_matches_golden(report: dict, expected: dict, path: str = "") -> None:
    """`report` equals the golden `expected` but for the masked members, numbers to a relative
    1e-9 (as `tissue_planner::golden` compares the other front ends' reports)."""
    if isinstance(expected, dict):
        assert isinstance(report, dict), path
        assert sorted(report) == sorted(expected), (path, sorted(report), sorted(expected))
        for key, value in expected.items():
            if value == "(masked)":
                continue
            assert_matches_golden(report[key], value, f"{path}.{key}")
    elif isinstance(expected, list):
        assert isinstance(report, list) and len(report) == len(expected), path
        for i, (a, b) in enumerate(zip(report, expected)):
            assert_matches_golden(a, b, f"{path}[{i}]")
    elif isinstance(expected, float) or (
        isinstance(expected, int) and not isinstance(expected, bool) and isinstance(report, float)
    ):
        assert report == pytest.approx(expected, rel=1e-9, abs=1e-12), path
    else:
        assert report == expected, path
