"""tissue.batch: population studies as independent tasks (issue 34, item 3).

Every planning case here is small (Table 2 or the fixture plane with `max_steps` 60), so the
whole file runs in well under a minute on 2 cores; the Dask test needs `dask.distributed`.
"""

from __future__ import annotations

import concurrent.futures as cf
from concurrent.futures.process import BrokenProcessPool
import json
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import pytest

import tissue
import tissue.batch as batch

REPO = Path(__file__).resolve().parents[2]
PLANE = REPO / "fixtures" / "plane_20cm_65.obj"
#: The plane's centre vertex (65 x 65 grid, row-major).
CENTRE = 32 * 65 + 32
FAST = {"max_steps": 60}
FIGURES_COMPARED = ("area_gain_cm2", "volume_difference_cm3", "steps", "residual_n", "stop_reason")


class Counting:
    """An executor that counts what it is given (threads in this process: fast, and enough
    for everything but the pickling, which the process tests cover)."""

    def __init__(self, inner=None):
        self.inner = inner or cf.ThreadPoolExecutor(2)
        self.submitted = 0
        self.lock = threading.Lock()

    def submit(self, fn, *args):
        with self.lock:
            self.submitted += 1
        return self.inner.submit(fn, *args)


@pytest.fixture
def executor():
    ex = Counting()
    yield ex
    if hasattr(ex.inner, "shutdown"):
        ex.inner.shutdown()


def table2(volume, **more):
    return {"patient": "table2", "volume_cm3": volume, **FAST, **more}


def result_files(out: Path):
    return sorted(p.name for p in out.iterdir())


def test_cases_from_dicts_are_planned_and_written_by_key(tmp_path, executor):
    cases = [table2(80), table2(120)]
    rows = batch.run(cases, tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 2
    assert [r["volume_cm3"] for r in rows] == [80, 120]
    for case, row in zip(cases, rows):
        assert row["error"] is None and row["error_kind"] is None
        assert row["patient"] == "table2" and row["max_steps"] == 60
        assert row["area_gain_cm2"] > 0 and row["volume_difference_cm3"] > 0
        assert row["steps"] is not None and row["wall_time_s"] is not None
        assert row["key"] == batch.case_key(case)
    # one file per case, named by its key, no temporary file left
    names = result_files(tmp_path / "out")
    assert names == sorted(f"{r['key']}.json" for r in rows)
    stored = json.loads((tmp_path / "out" / f"{rows[1]['key']}.json").read_text())
    assert stored["key"] == rows[1]["key"]
    assert stored["case"] == cases[1]
    assert stored["version"] == tissue.__version__
    assert stored["error"] is None
    assert stored["figures"]["area_gain_cm2"] == rows[1]["area_gain_cm2"]
    assert stored["report"]["area_gain_cm2"] == rows[1]["area_gain_cm2"]
    # more fill, more skin
    assert rows[1]["area_gain_cm2"] > rows[0]["area_gain_cm2"]


def test_the_key_is_canonical_and_follows_the_scan_and_the_version(tmp_path, monkeypatch):
    a = {"patient": "table2", "volume_cm3": 120, "max_steps": 60}
    b = {"max_steps": 60.0, "volume_cm3": 120.0, "patient": "table2"}
    assert batch.case_key(a) == batch.case_key(b)
    assert batch.case_key(a) != batch.case_key({**a, "volume_cm3": 121})
    assert len(batch.case_key(a)) == 64

    # a file is named by its content: moved, the same key; changed, another
    (tmp_path / "x").mkdir()
    shutil.copy(PLANE, tmp_path / "x" / "scan.obj")
    case = {"patient": "scan.obj", "vertex": CENTRE}
    k1 = batch.case_key(case, base=tmp_path / "x")
    k_abs = batch.case_key({**case, "patient": str(tmp_path / "x" / "scan.obj")})
    shutil.move(tmp_path / "x", tmp_path / "y")
    assert batch.case_key(case, base=tmp_path / "y") == k1 == k_abs
    with open(tmp_path / "y" / "scan.obj", "a") as f:
        f.write("# changed\n")
    assert batch.case_key(case, base=tmp_path / "y") != k1

    # a Path and NumPy numbers are the same case as their plain forms
    np = pytest.importorskip("numpy")
    assert batch.case_key({"patient": PLANE, "vertex": np.int64(CENTRE), "volume_cm3": np.float64(90)}) == batch.case_key(
        {"patient": str(PLANE), "vertex": CENTRE, "volume_cm3": 90}
    )

    # another library version recomputes
    monkeypatch.setattr(tissue, "__version__", tissue.__version__ + "+other")
    k_other = batch.case_key(a)
    monkeypatch.undo()
    assert batch.case_key(a) != k_other


def test_cases_from_a_jsonl_file_resolve_patients_beside_it(tmp_path, executor, monkeypatch):
    study = tmp_path / "study"
    (study / "scans").mkdir(parents=True)
    shutil.copy(PLANE, study / "scans" / "plane.obj")
    lines = [
        {"patient": "scans/plane.obj", "unit": "cm", "vertex": CENTRE, "volume_cm3": 90, **FAST},
        {"patient": "table2", "volume_cm3": 90, **FAST},
    ]
    cases_file = study / "cases.jsonl"
    cases_file.write_text("# a comment\n" + "\n".join(json.dumps(c) for c in lines) + "\n\n")
    monkeypatch.chdir(tmp_path)  # not the cases file's folder
    rows = batch.run(cases_file, tmp_path / "out", executor, as_frame=False)
    assert [r["error"] for r in rows] == [None, None], rows
    assert rows[0]["patient"] == "scans/plane.obj"  # the row shows the case as given
    assert rows[0]["area_gain_cm2"] > 0
    # and .json: the same cases, the same keys, nothing run again
    (study / "cases.json").write_text(json.dumps(lines))
    again = batch.run(study / "cases.json", tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 2
    assert again == rows


def test_cases_from_a_csv_file(tmp_path, executor):
    (tmp_path / "cases.csv").write_text(
        "patient,unit,vertex,volume_cm3,max_steps,diameter_cm,shape\n"
        "table2,,,70,60,6.5,round\n"
        "table2,,,75.5,60,,\n"
    )
    cases = batch.load_cases(tmp_path / "cases.csv")
    assert cases == [
        {"patient": "table2", "volume_cm3": 70, "max_steps": 60, "diameter_cm": 6.5, "shape": "round"},
        {"patient": "table2", "volume_cm3": 75.5, "max_steps": 60},
    ]
    assert isinstance(cases[0]["volume_cm3"], int) and isinstance(cases[1]["volume_cm3"], float)
    rows = batch.run(tmp_path / "cases.csv", tmp_path / "out", executor, as_frame=False)
    assert [r["error"] for r in rows] == [None, None], rows
    assert rows[0]["diameter_cm"] == 6.5


def test_a_failed_case_is_recorded_with_its_kind_and_the_batch_goes_on(tmp_path, executor):
    cases = [
        table2(100),
        table2(-5),
        table2(100, no_such_field=1),
        {"patient": str(tmp_path / "missing.ply"), "vertex": 3, **FAST},
        {"patient": "table2", "unit": "mm", **FAST},
        {"volume_cm3": 100},
    ]
    rows = batch.run(cases, tmp_path / "out", executor, as_frame=False)
    kinds = [(r["error_kind"], r["error_field"]) for r in rows]
    assert kinds[0] == (None, None)
    assert kinds[1] == ("parameters", "volume_cm3")
    assert kinds[2][0] == "usage"
    assert kinds[3] == ("input", "patient")
    assert kinds[4] == ("usage", "unit")
    assert kinds[5] == ("usage", "patient")
    assert rows[1]["error"].startswith("parameters: ") and "volume_cm3" in rows[1]["error"]
    assert rows[1]["area_gain_cm2"] is None
    # the planner's failures are recorded (a rerun does not repeat them); the cases that could
    # not be sent (no file, no patient) are not: a rerun tries them again
    stored = json.loads((tmp_path / "out" / f"{rows[1]['key']}.json").read_text())
    assert stored["error"]["kind"] == "parameters" and stored["error"]["field"] == "volume_cm3"
    assert stored["report"] is None
    assert executor.submitted == 3
    assert len(result_files(tmp_path / "out")) == 3
    again = batch.run(cases, tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 3
    assert again == rows


def test_a_rerun_resumes_and_only_a_new_case_is_run(tmp_path, executor):
    cases = [table2(v) for v in (60, 70, 80)]
    progress = []
    first = batch.run(cases, tmp_path / "out", executor, as_frame=False, progress=lambda d, t: progress.append((d, t)))
    assert executor.submitted == 3
    assert progress[0] == (0, 3) and progress[-1] == (3, 3)
    again = batch.run(cases, tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 3
    assert again == first
    # a crash half-way leaves whole files only: drop one result, and a temporary file a killed
    # driver could leave, and rerun with a new case
    os.remove(tmp_path / "out" / f"{first[0]['key']}.json")
    (tmp_path / "out" / f".{first[0]['key']}.json.tmp-1-x").write_text("{")
    more = batch.run(cases + [table2(90)], tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 5
    assert more[1:3] == first[1:3]
    assert _figures(more[0]) == _figures(first[0])  # planned again: only its wall time differs
    assert not [n for n in result_files(tmp_path / "out") if ".tmp-" in n and not n.endswith("-x")]
    assert more[3]["error"] is None
    # the same case twice is run once
    twice = batch.run([table2(95), table2(95.0)], tmp_path / "out", executor, as_frame=False)
    assert executor.submitted == 6
    assert twice[0]["key"] == twice[1]["key"]


def test_a_worker_without_the_file_gets_it_sent_and_a_changed_file_is_refused(tmp_path):
    scan = tmp_path / "scan.obj"
    shutil.copy(PLANE, scan)
    case = {"patient": str(scan), "vertex": CENTRE, "volume_cm3": 70, **FAST}

    class Elsewhere:
        """Runs each task where the driver's file is not (moved away while it runs)."""

        def __init__(self, change=False):
            self.change = change

        def submit(self, fn, *args):
            f = cf.Future()
            if self.change:
                with open(scan, "a") as out:
                    out.write("# changed after keying\n")
                f.set_result(fn(*args))
            else:
                os.rename(scan, tmp_path / "away.obj")
                try:
                    f.set_result(fn(*args))
                finally:
                    os.rename(tmp_path / "away.obj", scan)
            return f

    sent = batch.run([case], tmp_path / "sent", Elsewhere(), send_files=True, as_frame=False)
    assert sent[0]["error"] is None and sent[0]["area_gain_cm2"] > 0
    # without it, the worker says so, and that is not recorded as the case's answer
    unsent = batch.run([case], tmp_path / "unsent", Elsewhere(), as_frame=False)
    assert (unsent[0]["error_kind"], unsent[0]["error_field"]) == ("input", "patient")
    assert "is not on this worker" in unsent[0]["error"] and result_files(tmp_path / "unsent") == []
    changed = batch.run([case], tmp_path / "changed", Elsewhere(change=True), as_frame=False)
    assert (changed[0]["error_kind"], changed[0]["error_field"]) == ("input", "patient")
    assert "is not the one the batch keyed" in changed[0]["error"]
    assert result_files(tmp_path / "changed") == []  # not this key's answer: a rerun retries


def test_a_lost_worker_is_not_recorded_and_a_rerun_retries(tmp_path):
    class Broken:
        submitted = 0

        def submit(self, fn, *args):
            self.submitted += 1
            f = cf.Future()
            f.set_exception(BrokenProcessPool("a worker died"))
            return f

    rows = batch.run([table2(100)], tmp_path / "out", Broken(), as_frame=False)
    assert rows[0]["error_kind"] == "worker" and "BrokenProcessPool" in rows[0]["error"]
    assert result_files(tmp_path / "out") == []
    ok = Counting()
    assert batch.run([table2(100)], tmp_path / "out", ok, as_frame=False)[0]["error"] is None
    assert ok.submitted == 1


def test_an_executor_of_other_futures_is_polled(tmp_path):
    class Lazy:
        """Futures with .done() and .result() only (not concurrent.futures)."""

        class F:
            def __init__(self, fn, args):
                self.fn, self.args, self.value = fn, args, None

            def done(self):
                return True

            def result(self):
                return self.fn(*self.args)

        def submit(self, fn, *args):
            return self.F(fn, args)

    rows = batch.run([table2(100), table2(110)], tmp_path / "out", Lazy(), as_frame=False)
    assert [r["error"] for r in rows] == [None, None]


def test_a_dataframe_when_pandas_is_there_and_a_list_otherwise(tmp_path, executor, monkeypatch):
    pandas = pytest.importorskip("pandas")
    frame = batch.run([table2(100)], tmp_path / "out", executor)
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame["volume_cm3"]) == [100] and frame["error"].isna().all()
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now raises ImportError
    rows = batch.run([table2(100)], tmp_path / "out", executor)
    assert isinstance(rows, list) and rows[0]["volume_cm3"] == 100


def _figures(row):
    return {k: row[k] for k in FIGURES_COMPARED}


def test_the_same_case_gives_the_same_numbers_in_any_process_and_thread_count(tmp_path):
    cases = [table2(90), {"patient": str(PLANE), "vertex": CENTRE, "volume_cm3": 60, **FAST}]
    here = [batch._run_case(c) for c in cases]
    assert [r["error"] for r in here] == [None, None]
    # two spawned worker processes (the default pool, one planner thread each)
    pooled = batch.run(cases, tmp_path / "pool", workers=2, as_frame=False)
    assert [_figures(r) for r in pooled] == [{k: r["figures"][k] for k in FIGURES_COMPARED} for r in here]
    # one and two planner threads
    script = (
        "import json, sys, tissue.batch as b;"
        "print(json.dumps([b._run_case(c)['figures'] for c in json.loads(sys.argv[1])]))"
    )
    seen = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        out = subprocess.run(
            [sys.executable, "-c", script, json.dumps(cases)], env=env, capture_output=True, text=True, check=True
        )
        seen.append([{k: f[k] for k in FIGURES_COMPARED} for f in json.loads(out.stdout)])
    assert seen[0] == seen[1] == [_figures(r) for r in pooled]


def test_a_dask_cluster_of_two_worker_processes_runs_a_batch_and_resumes(tmp_path):
    distributed = pytest.importorskip("distributed")
    cases = [table2(v) for v in range(60, 130, 10)] + [table2(-5)]
    assert len(cases) == 8
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env={"RAYON_NUM_THREADS": "1"},
    ) as cluster, distributed.Client(cluster) as client:
        counting = Counting(client)
        rows = batch.run(cases, tmp_path / "out", counting, as_frame=False)
        assert counting.submitted == 8
        assert [r["error_kind"] for r in rows] == [None] * 7 + ["parameters"]
        assert len(result_files(tmp_path / "out")) == 8
        # the tasks ran on both workers (processes other than this one)
        pids = {json.loads((tmp_path / "out" / f"{r['key']}.json").read_text())["worker"]["pid"] for r in rows}
        assert os.getpid() not in pids
        # resume: one result lost, only it runs again, the table is the same
        os.remove(tmp_path / "out" / f"{rows[3]['key']}.json")
        again = batch.run(cases, tmp_path / "out", counting, as_frame=False)
        assert counting.submitted == 9
        assert [_figures(r) for r in again] == [_figures(r) for r in rows]
        assert again[:3] == rows[:3] and again[4:] == rows[4:]
        # the command line on the same cluster: a new case runs on one of its workers
        cases_file = tmp_path / "cases.jsonl"
        cases_file.write_text("\n".join(json.dumps(c) for c in cases + [table2(135)]) + "\n")
        cli = subprocess.run(
            [sys.executable, "-m", "tissue.batch", str(cases_file), "--out", str(tmp_path / "out"),
             "--scheduler", cluster.scheduler_address, "--json", "--quiet"],
            capture_output=True, text=True,
        )
        assert cli.returncode == 1, cli.stderr  # the failing case, recorded, still counts
        cli_rows = [json.loads(line) for line in cli.stdout.splitlines()]
        assert [r["key"] for r in cli_rows] == [r["key"] for r in again] + [batch.case_key(table2(135))]
        assert cli_rows[-1]["error"] is None
        new = json.loads((tmp_path / "out" / f"{cli_rows[-1]['key']}.json").read_text())
        assert new["worker"]["pid"] in set(client.run(os.getpid).values())


def test_the_command_line(tmp_path):
    cases = tmp_path / "cases.jsonl"
    cases.write_text("\n".join(json.dumps(c) for c in [table2(100), table2(-5), table2(110)]) + "\n")
    cmd = [sys.executable, "-m", "tissue.batch", str(cases), "--out", str(tmp_path / "out"), "--workers", "2"]
    run = subprocess.run(cmd + ["--json"], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 1, run.stderr
    rows = [json.loads(line) for line in run.stdout.splitlines()]
    assert [r["error_kind"] for r in rows] == [None, "parameters", None]
    assert "1 of 3 cases failed" in run.stderr
    assert len(result_files(tmp_path / "out")) == 3
    # the table, resumed from the files
    table = subprocess.run(cmd + ["--quiet"], capture_output=True, text=True, cwd=tmp_path)
    assert table.returncode == 1
    header = table.stdout.splitlines()[0].split()
    assert header[:2] == ["key", "patient"] and "area_gain_cm2" in header and header[-1] == "error"
    # every case ran: 0
    ok = tmp_path / "ok.jsonl"
    ok.write_text(json.dumps(table2(100)) + "\n")
    assert subprocess.run(cmd[:3] + [str(ok), "--out", str(tmp_path / "out"), "--quiet"], cwd=tmp_path).returncode == 0
    # usage errors: 2
    assert subprocess.run(cmd[:4], capture_output=True, cwd=tmp_path).returncode == 2
    bad = subprocess.run(cmd[:3] + [str(tmp_path / "cases.txt"), "--out", "o"], capture_output=True, text=True, cwd=tmp_path)
    assert bad.returncode == 2 and "cases" in bad.stderr


def test_a_ray_executor_runs_a_batch(tmp_path):
    ray = pytest.importorskip("ray")  # not in CI's venv (a large wheel): run by hand with ray installed
    if not hasattr(ray, "init"):  # a folder called ray (Ray's own /tmp/ray) is not Ray
        pytest.skip("ray is not installed")
    ray.init(num_cpus=2, include_dashboard=False, runtime_env={"env_vars": {"RAYON_NUM_THREADS": "1"}})
    try:
        rows = batch.run([table2(60), table2(-5)], tmp_path / "out", batch.RayExecutor(num_cpus=1), as_frame=False)
    finally:
        ray.shutdown()
    assert [r["error_kind"] for r in rows] == [None, "parameters"]
    assert rows[0]["area_gain_cm2"] > 0
