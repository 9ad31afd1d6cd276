"""Every planning mode through Python gives the golden report of `fixtures/reports/` (the one
insert, the studio and the C ABI give), through the job JSON and through the keyword API."""

from __future__ import annotations

import json

import pytest

import tissue

from conftest import assert_matches_golden, fixture, golden


@pytest.fixture(scope="module")
def table2() -> tissue.Patient:
    return tissue.Patient.shipped("table2")


@pytest.mark.parametrize("name", ["sweep", "target-gain", "expansion"])
def test_each_golden_job_gives_its_golden_report(table2: tissue.Patient, name: str) -> None:
    job = json.loads(fixture(f"reports/{name}.job.json").read_text())
    plan = tissue.run_job(table2, job)
    assert plan.mode == name
    assert plan.report["tool"] == "python"
    assert_matches_golden(plan.report, golden(name))


def test_sweep_keywords_are_the_jobs_members(table2: tissue.Patient) -> None:
    plan = tissue.sweep(table2, [20, 40, 4000], max_steps=300, solver="explicit")
    assert_matches_golden(plan.report, golden("sweep"))
    runs = plan.report["runs"]
    assert [r["volume_cm3"] for r in runs] == [20.0, 40.0]
    failed = plan.report["failed_runs"]
    assert failed[0]["volume_cm3"] == 4000.0 and failed[0]["error"]["field"] == "volume_cm3"
    assert plan.area_gain_cm2 is None and plan.vertices_after is None


def test_target_gain_keywords(table2: tissue.Patient) -> None:
    plan = tissue.target_gain(table2, 20.0, gain_tolerance_cm2=1.0, max_steps=2000)
    assert_matches_golden(plan.report, golden("target-gain"))
    assert plan.volume_cm3 == plan.report["volume_cm3"]
    assert abs(plan.area_gain_cm2 - 20.0) <= 1.0
    with pytest.raises(tissue.PlanError) as e:
        tissue.target_gain(table2, 20.0, bracket_cm3=(50, 10))
    assert e.value.field == "bracket_cm3"


def test_expand_keywords_give_the_weekly_table_and_band(table2: tissue.Patient) -> None:
    plan = tissue.expand(table2, 2, band_samples=16)
    assert_matches_golden(plan.report, golden("expansion"))
    # A row per weekly fill, then the end of the protocol.
    assert [w["week"] for w in plan.report["weeks"]][:2] == [0, 1]
    assert "band" in plan.report and plan.mode == "expansion"
    with pytest.raises(tissue.PlanError) as e:
        tissue.expand(table2, 2, leakage=2.0)
    assert e.value.field == "leakage"


def test_a_bad_sweep_names_its_member(table2: tissue.Patient) -> None:
    with pytest.raises(tissue.PlanError) as e:
        tissue.sweep(table2, [])
    assert e.value.field == "volumes_cm3"
    with pytest.raises(tissue.PlanError) as e:
        tissue.run_job(table2, {"mode": "sweep", "volumes": [1]})
    assert e.value.kind == "usage"
