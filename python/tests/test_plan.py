"""Planning through Python: Table 2 against the thesis's band and the golden report, a scan
from arrays in its own unit, the request's names, and each error's class."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

import tissue

from conftest import assert_matches_golden, fixture, golden

# Table 2, 100 cm³: the thesis's gain and the band the insert and C ABI tests use (± 25 %).
THESIS_GAIN_CM2 = 31.43
BAND = (0.75 * THESIS_GAIN_CM2, 1.25 * THESIS_GAIN_CM2)


@pytest.fixture(scope="module")
def table2() -> tissue.Patient:
    return tissue.Patient.shipped("table2")


@pytest.fixture(scope="module")
def table2_plan(table2: tissue.Patient) -> tissue.Plan:
    return tissue.plan(table2)


def test_version_and_fields() -> None:
    assert tissue.__version__.count(".") == 2
    assert tissue.REPORT_SCHEMA_VERSION == 1
    for name in ("shape", "diameter_cm", "volume_cm3", "depth_cm", "sim_edge_cm", "expand_weeks", "vertex", "at"):
        assert name in tissue.REQUEST_FIELDS


def test_table2_is_within_the_thesis_band_and_the_golden_report(table2_plan: tissue.Plan) -> None:
    plan = table2_plan
    assert plan.mode == "single"
    assert BAND[0] <= plan.area_gain_cm2 <= BAND[1], plan.area_gain_cm2
    assert plan.area_gain_cm2 == pytest.approx(34.98, abs=0.01)
    # The same report as insert, the studio and the C ABI give (but for tool, version, wall).
    report = plan.report
    assert report["tool"] == "python"
    assert report["version"] == tissue.__version__
    assert_matches_golden(report, golden("single"))
    assert json.loads(plan.report_json) == report
    assert plan.area_gain_cm2 == report["area_gain_cm2"]
    assert plan.volume_difference_cm3 == report["volume_difference_cm3"]
    assert plan.volume_cm3 == 100.0


def test_table2_results_are_per_vertex_arrays(table2: tissue.Patient, table2_plan: tissue.Plan) -> None:
    n = len(table2)
    assert table2.vertices.shape == (n, 3) and table2.vertices.dtype == np.float64
    assert table2.triangles.shape == (8192, 3) and table2.triangles.dtype == np.int64
    plan = table2_plan
    assert plan.vertices_after.shape == (n, 3)
    for field in (plan.displacement, plan.stretch, plan.in_region):
        assert field.shape == (n,) and field.dtype == np.float64
    moved = np.linalg.norm(plan.vertices_after - table2.vertices, axis=1)
    np.testing.assert_allclose(moved, plan.displacement, atol=1e-5)
    assert plan.displacement.max() == pytest.approx(plan.report["max_displacement_cm"], rel=1e-6)
    assert int(plan.in_region.sum()) == plan.report["region_vertices"]
    inside = plan.in_region > 0
    assert (plan.stretch[inside] > 0).all() and (plan.stretch[~inside] == 0).all()
    # The dome rises over the implant: +z at the centre vertex.
    centre = table2.suggested_vertex
    assert plan.vertices_after[centre, 2] > 3.0


def test_a_scan_from_arrays_in_mm_is_mapped_back_with_its_own_vertex_count() -> None:
    # A noisy 20 cm skin patch scanned in mm, its own irregular grid (not the planner's).
    rng = np.random.default_rng(7)
    nx, ny = 47, 43
    xs, ys = np.meshgrid(np.linspace(-100, 100, nx), np.linspace(-100, 100, ny), indexing="xy")
    z = rng.normal(0.0, 0.15, size=xs.shape)
    vertices = np.stack([xs, ys, z], axis=-1).reshape(-1, 3).astype(np.float32)
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    triangles = np.concatenate(
        [np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    ).astype(np.int32)
    scan = tissue.Patient.from_arrays(vertices, triangles, unit="mm")
    assert scan.unit == "mm" and len(scan) == nx * ny
    np.testing.assert_array_equal(scan.vertices, vertices.astype(np.float64))
    centre = int(idx[ny // 2, nx // 2])
    plan = tissue.plan(scan, vertex=centre, volume_cm3=60, diameter_cm=6, sim_edge_cm=0.6, max_steps=4000)
    assert plan.vertices_after.shape == (nx * ny, 3)
    assert plan.displacement.shape == (nx * ny,)
    assert plan.report["inputs"]["unit"] == "mm"
    assert plan.report["inputs"]["mesh_vertices"] == nx * ny
    # Positions and displacements come back in the scan's unit (mm): ten times the cm figures.
    moved = np.linalg.norm(plan.vertices_after - scan.vertices, axis=1)
    np.testing.assert_allclose(moved, plan.displacement, atol=1e-3)
    top_mm = plan.displacement.max()
    assert 5.0 * plan.report["max_displacement_cm"] < top_mm < 12.0 * plan.report["max_displacement_cm"]
    assert plan.vertices_after[centre, 2] > 10.0  # a dome of more than 1 cm, in mm
    assert plan.area_gain_cm2 > 0


def test_a_shipped_patch_loads_in_its_unit() -> None:
    chest = tissue.Patient.shipped("chest")
    assert chest.unit == "dm" and chest.cm_per_unit == 10.0
    loaded = tissue.Patient.load(fixture("makehuman_chest_open.obj"), unit="dm")
    np.testing.assert_array_equal(loaded.vertices, chest.vertices)
    np.testing.assert_array_equal(loaded.triangles, chest.triangles)


def test_an_unknown_request_name_is_refused_by_name(table2: tissue.Patient) -> None:
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, volume=100)
    assert e.value.field == "volume" and e.value.kind == "usage"
    assert "volume_cm3" in str(e.value), "the message lists the fields"
    assert isinstance(e.value, tissue.TissueError)


def test_bad_values_name_their_field(table2: tissue.Patient) -> None:
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, volume_cm3=-5)
    assert (e.value.kind, e.value.field) == ("parameters", "volume_cm3")
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, volume_cm3="lots")
    assert (e.value.kind, e.value.field) == ("usage", "volume_cm3")
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, shape="square")
    assert e.value.field == "shape"
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, depth_cm=float("nan"))
    assert e.value.field == "depth_cm"
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, shape="rectangular", length_cm=8)
    assert (e.value.kind, e.value.field) == ("usage", "width_cm")
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, expand_weeks=3)
    assert e.value.field == "expand_weeks"
    with pytest.raises(tissue.PlanError) as e:
        tissue.plan(table2, vertex=10**6)
    assert e.value.field in ("vertex", "at")
    with pytest.raises(tissue.PlanError) as e:
        tissue.Patient.shipped("knee")
    assert e.value.field == "name"
    with pytest.raises(tissue.PlanError) as e:
        tissue.Patient.load(fixture("makehuman_chest_open.obj"), unit="inch")
    assert e.value.field == "unit"


def test_arrays_of_the_wrong_shape_or_type_raise_mesh_errors() -> None:
    triangles = np.array([[0, 1, 2]])
    with pytest.raises(tissue.MeshError) as e:
        tissue.Patient.from_arrays(np.zeros((3, 2)), triangles)
    assert e.value.field == "vertices" and isinstance(e.value, ValueError)
    with pytest.raises(ValueError):
        tissue.Patient.from_arrays(np.zeros(9), triangles)
    with pytest.raises(tissue.MeshError) as e:
        tissue.Patient.from_arrays(np.eye(3), np.array([[0.0, 1.0, 2.0]]))
    assert e.value.field == "triangles"
    with pytest.raises(tissue.MeshError) as e:
        tissue.Patient.from_arrays(np.eye(3), np.array([[0, 1, 3]]))
    assert e.value.field == "triangles"
    with pytest.raises(tissue.MeshError) as e:
        tissue.Patient.from_arrays(np.eye(3), np.array([[0, 1, -1]]))
    assert e.value.field == "triangles"
    with pytest.raises(tissue.MeshError):
        tissue.Patient.from_arrays(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), triangles)


def test_a_missing_or_malformed_file_raises_an_input_or_mesh_error(tmp_path) -> None:
    with pytest.raises(tissue.InputError) as e:
        tissue.Patient.load(tmp_path / "nowhere.obj")
    assert isinstance(e.value, OSError) and isinstance(e.value, tissue.MeshError)
    assert e.value.kind == "input" and e.value.field == "mesh"
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(tissue.MeshError) as e:
        tissue.Patient.load(bad)
    assert e.value.kind == "mesh" and not isinstance(e.value, OSError)


def test_progress_is_called_on_the_calling_thread_and_false_cancels(table2: tissue.Patient) -> None:
    calls = []

    def progress(step: int, max_steps: int, settle: float) -> bool:
        calls.append((threading.get_ident(), step, max_steps, settle))
        return len(calls) < 3

    with pytest.raises(tissue.Cancelled) as e:
        tissue.plan(table2, time_step_s=1e-6, max_steps=20000, progress=progress)
    assert e.value.kind == "cancelled" and isinstance(e.value, tissue.PlanError)
    assert len(calls) == 3
    assert {c[0] for c in calls} == {threading.get_ident()}
    assert all(0 < c[1] <= c[2] == 20000 and 0.0 <= c[3] <= 1.0 for c in calls)


def test_an_exception_in_progress_cancels_and_propagates(table2: tissue.Patient) -> None:
    def progress(step: int, max_steps: int, settle: float) -> None:
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        tissue.plan(table2, time_step_s=1e-6, max_steps=20000, progress=progress)


def test_a_progress_that_returns_none_does_not_cancel(table2: tissue.Patient) -> None:
    steps = []
    plan = tissue.plan(table2, max_steps=60, progress=lambda s, m, _: steps.append(s))
    assert plan.report["steps"] == 60 and steps and max(steps) <= 60


def test_placement_by_point_or_default_vertex() -> None:
    table2 = tissue.Patient.shipped("table2")
    plan = tissue.plan(table2, at=np.array([1.0, 0.5, 0.0]), max_steps=10)
    assert plan.report["inputs"]["at"] == [1.0, 0.5, 0.0]
    assert plan.report["inputs"]["surface_point_cm"] == pytest.approx([1.0, 0.5, 0.0])
    # A shipped patch runs at its suggested vertex when no placement is given; its results
    # come back in its unit (dm): a tenth of the cm figures.
    chest = tissue.Patient.shipped("chest")
    plan = tissue.plan(chest, max_steps=50)
    assert plan.report["inputs"]["vertex"] == chest.suggested_vertex == 2277
    assert plan.report["inputs"]["unit"] == "dm"
    assert plan.displacement.max() == pytest.approx(plan.report["max_displacement_cm"] / 10, rel=0.05)


def test_patients_and_plans_pickle_for_dask_workers(table2_plan: tissue.Plan) -> None:
    import pickle

    for patient in (
        tissue.Patient.shipped("head"),
        tissue.Patient.from_arrays(np.eye(3), np.array([[0, 1, 2]]), unit="mm", label="one"),
    ):
        back = pickle.loads(pickle.dumps(patient))
        np.testing.assert_array_equal(back.vertices, patient.vertices)
        np.testing.assert_array_equal(back.triangles, patient.triangles)
        assert (back.unit, back.label, back.shipped_name) == (patient.unit, patient.label, patient.shipped_name)
    back = pickle.loads(pickle.dumps(table2_plan))
    assert back.report == table2_plan.report and back.report_json == table2_plan.report_json
    assert (back.mode, back.area_gain_cm2, back.volume_difference_cm3, back.volume_cm3) == (
        table2_plan.mode,
        table2_plan.area_gain_cm2,
        table2_plan.volume_difference_cm3,
        table2_plan.volume_cm3,
    )
    np.testing.assert_array_equal(back.vertices_after, table2_plan.vertices_after)
    np.testing.assert_array_equal(back.stretch, table2_plan.stretch)
