"""Population studies: many planning cases as independent tasks, on any executor.

``run(cases, out_dir, executor=None)`` plans every case (a dict such as
``{"patient": "scans/p17.ply", "unit": "mm", "vertex": 812, "volume_cm3": 120}``, or a
CSV / JSON-lines / JSON file of them) as one task on ``executor`` (anything with
``submit(fn, *args)``: ``concurrent.futures.ProcessPoolExecutor``, a
``dask.distributed.Client``, :class:`RayExecutor`; default: a local process pool), writes each
result to ``out_dir/<key>.json`` atomically, skips cases whose result is already there (a
rerun after a crash resumes) and returns a summary table, one row per case.

From a shell::

    python -m tissue.batch cases.jsonl --out results/ [--scheduler tcp://host:8786]

docs/python.md has the details: the case's fields, the key, the result files, the clusters.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import hashlib
import json
import math
import multiprocessing
import os
import socket
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

__all__ = ["run", "load_cases", "case_key", "RayExecutor", "SHIPPED", "main"]

#: The patients shipped with the library: a case's ``patient`` naming one of these loads it
#: (``Patient.shipped``); anything else is a file path (write ``./chest`` for a file called
#: ``chest``).
SHIPPED = ("table2", "chest", "head")

#: The key figures copied from every result into the summary row (``None`` where a mode's
#: report has no such field).
FIGURES = ("area_gain_cm2", "volume_difference_cm3", "steps", "residual_n", "stop_reason", "wall_time_s")

#: The result file's format; raised on a change that is not an addition.
RESULT_FORMAT = 1

_READ_CHUNK = 1 << 20


# --------------------------------------------------------------------------------------------
# Cases: reading, resolving, keying
# --------------------------------------------------------------------------------------------


class _CaseError(Exception):
    """A case that cannot even be sent (no patient, a missing file, an unhashable value)."""

    def __init__(self, kind: str, field: str | None, message: str):
        super().__init__(message)
        self.kind = kind
        self.field = field
        self.message = message


#: CSV columns kept as text (a scan called ``17.ply`` is not a number, nor a unit).
_TEXT_FIELDS = ("patient", "unit")


def _parse_cell(text: str) -> Any:
    """A CSV cell: an int or a float when it parses as one, true/false, a JSON list
    (``[1.5, 2, 0]`` for ``at`` or ``tangent``), else the text."""
    t = text.strip()
    try:
        return int(t)
    except ValueError:
        pass
    try:
        v = float(t)
    except ValueError:
        pass
    else:
        if math.isfinite(v):
            return v
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    if t.startswith("["):
        try:
            return json.loads(t)
        except ValueError:
            pass
    return t


def load_cases(path: str | os.PathLike) -> list[dict]:
    """The cases of a ``.jsonl`` (one JSON object a line; blank lines and lines starting
    with ``#`` skipped), ``.json`` (a list of objects) or ``.csv`` file (a header row of field
    names; numbers parsed to int or float when they parse, empty cells dropped)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        with open(p, newline="", encoding="utf-8") as f:
            cases = []
            for row in csv.DictReader(f):
                cases.append(
                    {
                        k.strip(): (v.strip() if k.strip() in _TEXT_FIELDS else _parse_cell(v))
                        for k, v in row.items()
                        if k and isinstance(v, str) and v.strip() != ""
                    }
                )
            return cases
    if suffix in (".jsonl", ".ndjson"):
        cases = []
        with open(p, encoding="utf-8") as f:
            for n, line in enumerate(f, 1):
                s = line.strip()
                if not s or s.startswith("#"):
                    continue
                try:
                    case = json.loads(s)
                except ValueError as e:
                    raise ValueError(f"{p}:{n}: not a JSON object: {e}") from None
                if not isinstance(case, dict):
                    raise ValueError(f"{p}:{n}: a case is a JSON object, not {type(case).__name__}")
                cases.append(case)
        return cases
    if suffix == ".json":
        with open(p, encoding="utf-8") as f:
            data = json.load(f)
        if not isinstance(data, list) or not all(isinstance(c, dict) for c in data):
            raise ValueError(f"{p}: a .json cases file is a list of objects")
        return data
    raise ValueError(f"{p}: cases are read from .jsonl, .json or .csv files, not {suffix or 'no suffix'}")


def _canonical(value: Any) -> Any:
    """The value as it is keyed: whole floats as ints (``120.0`` and ``120`` are one case),
    tuples as lists; NaN and infinities refused."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError("NaN and infinities cannot be planned")
        return int(value) if value.is_integer() and abs(value) < 2**53 else value
    if isinstance(value, Mapping):
        return {str(k): _canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    # numpy scalars and arrays, without importing numpy
    if hasattr(value, "tolist"):
        return _canonical(value.tolist())
    raise TypeError(f"a case's values are numbers, strings, booleans or lists, not {type(value).__name__}")


def _canonical_json(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def _file_sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while True:
            chunk = f.read(_READ_CHUNK)
            if not chunk:
                break
            h.update(chunk)
    return h.hexdigest()


def _version() -> str:
    import tissue

    return tissue.__version__


class _Prepared:
    """One case as given, as sent, and its key (or why it cannot be sent)."""

    __slots__ = ("given", "task", "key", "error")

    def __init__(self, given: dict, task: dict | None, key: str, error: _CaseError | None):
        self.given = given
        self.task = task
        self.key = key
        self.error = error


def _prepare(given: Mapping, base: Path, version: str, hashes: dict[str, str]) -> _Prepared:
    given = dict(given)
    try:
        case = _canonical(given)
    except (TypeError, ValueError) as e:
        key = hashlib.sha256(repr(sorted(given.items(), key=lambda kv: str(kv[0]))).encode()).hexdigest()
        return _Prepared(given, None, key, _CaseError("usage", None, f"the case cannot be keyed: {e}"))
    patient = case.get("patient")
    identity = dict(case)
    identity.pop("patient", None)
    task: dict | None = None
    error: _CaseError | None = None
    if not isinstance(patient, str) or not patient:
        error = _CaseError("usage", "patient", "a case needs `patient`: a file path or a shipped name " + "/".join(SHIPPED))
        identity["patient"] = patient
    elif patient in SHIPPED:
        identity["patient"] = {"shipped": patient}
        if "unit" in case:
            error = _CaseError(
                "usage", "unit", f"`unit` is for a patient file; the shipped `{patient}` knows its own unit"
            )
        task = {"case": case, "shipped": patient}
    else:
        path = Path(os.path.expanduser(patient))
        if not path.is_absolute():
            path = base / path
        resolved = str(path.resolve())
        try:
            digest = hashes.get(resolved)
            if digest is None:
                digest = hashes[resolved] = _file_sha256(resolved)
        except OSError as e:
            error = _CaseError("input", "patient", f"cannot read the patient file {resolved}: {e.strerror or e}")
            identity["patient"] = {"path": resolved}
        else:
            # The file's content, not its path, names the patient: a moved folder is not
            # recomputed, a changed scan is.
            identity["patient"] = {"sha256": digest, "suffix": path.suffix.lower()}
            task = {"case": case, "path": resolved, "sha256": digest}
    identity_doc = {"case": identity, "tissue": version}
    key = hashlib.sha256(_canonical_json(identity_doc).encode("utf-8")).hexdigest()
    if error is not None:
        task = None
    return _Prepared(given, task, key, error)


def case_key(case: Mapping, *, base: str | os.PathLike | None = None) -> str:
    """The key of ``case`` (its result file is ``<key>.json``): the SHA-256 of the canonical
    JSON (sorted keys, no whitespace, whole floats as ints) of the case with ``patient``
    replaced by the shipped name or the patient file's SHA-256 and suffix, and the library's
    version. Relative paths are resolved against ``base`` (default: the current folder)."""
    base_path = Path(base) if base is not None else Path.cwd()
    return _prepare(case, base_path, _version(), {}).key


# --------------------------------------------------------------------------------------------
# The task: runs on a worker
# --------------------------------------------------------------------------------------------

_PLACEMENT = ("vertex", "at")


def _figures(report: Mapping | None, plan: Any = None) -> dict:
    out = {}
    for name in FIGURES:
        value = None
        if plan is not None and name in ("area_gain_cm2", "volume_difference_cm3"):
            value = getattr(plan, name, None)
        if value is None and isinstance(report, Mapping):
            value = report.get(name)
        out[name] = value
    return out


def _run_case(case: dict, shipped: str | None = None, path: str | None = None,
              sha256: str | None = None, data: bytes | None = None) -> dict:
    """Plans one case and returns its JSON-able result: the case, ``figures``, the full
    ``report``, the library ``version`` and ``error`` (None, or ``{"kind", "field",
    "message"}``). A ``tissue.TissueError`` is recorded with its kind; any other exception as
    kind ``internal`` (its type and message). A worker that cannot import tissue raises.

    ``case`` is the case as given (``patient`` and ``unit`` say what to load, every other
    field goes to ``tissue.plan``); ``shipped`` or ``path`` (with the file's ``sha256``, checked
    on the worker, and optionally its bytes ``data`` for workers without the file) say what
    ``patient`` was resolved to. Called with the case alone, it resolves ``patient`` itself
    (a shipped name, or a path from the current folder)."""
    import tissue  # a worker without tissue raises here: the batch records a `worker` error

    started = time.perf_counter()
    result: dict = {
        "format": RESULT_FORMAT,
        "case": case,
        "version": tissue.__version__,
        "error": None,
        "figures": _figures(None),
        "report": None,
        "worker": {"host": socket.gethostname(), "pid": os.getpid()},
    }
    tmpdir = None
    try:
        case = dict(case)
        patient_name = case.pop("patient", None)
        unit = case.pop("unit", None)
        if shipped is None and path is None:
            if patient_name in SHIPPED:
                shipped = patient_name
            elif isinstance(patient_name, str):
                path = str(Path(patient_name).resolve())
            else:
                result["error"] = {"kind": "usage", "field": "patient", "message": "a case needs `patient`"}
                return result
        if shipped is not None:
            patient = tissue.Patient.shipped(shipped)
        else:
            assert path is not None
            if data is not None:
                tmpdir = tempfile.mkdtemp(prefix="tissue-batch-")
                local = os.path.join(tmpdir, "patient" + Path(path).suffix.lower())
                with open(local, "wb") as f:
                    f.write(data)
            else:
                local = path
                if sha256 is not None and not os.path.exists(local):
                    result["error"] = {
                        "kind": "input",
                        "field": "patient",
                        "message": f"the patient file {path} is not on this worker ({socket.gethostname()}): "
                        "pass send_files=True (--send-files) for workers without the driver's files",
                    }
                    result["transient"] = True  # the worker's, not the case's: a rerun retries
                    return result
            if sha256 is not None:
                try:
                    seen = _file_sha256(local)
                except OSError:
                    seen = None  # tissue's own load says what is wrong with the path
                if seen is not None and seen != sha256:
                    result["error"] = {
                        "kind": "input",
                        "field": "patient",
                        "message": f"the patient file {path} on this worker is not the one the batch keyed "
                        f"(SHA-256 {seen[:12]}…, not {sha256[:12]}…): changed during the batch, or another "
                        "machine's copy; pass send_files=True (--send-files) for workers without the file",
                    }
                    result["transient"] = True  # not this case's answer: not recorded, a rerun retries
                    return result
            patient = tissue.Patient.load(local, unit=unit) if unit is not None else tissue.Patient.load(local)
        placement = {k: case.pop(k) for k in _PLACEMENT if k in case}
        plan = tissue.plan(patient, **placement, **case)
        report = plan.report
        result["report"] = report
        result["figures"] = _figures(report, plan)
    except tissue.TissueError as e:
        result["error"] = {
            "kind": getattr(e, "kind", None) or _error_kind_of(tissue, e),
            "field": getattr(e, "field", None),
            "message": str(e),
        }
    except Exception as e:  # never let one case take the batch down
        result["error"] = {
            "kind": "internal",
            "field": None,
            "message": f"{type(e).__name__}: {e}",
            "traceback": traceback.format_exc(limit=8),
        }
    finally:
        if tmpdir is not None:
            import shutil

            shutil.rmtree(tmpdir, ignore_errors=True)
        result["task_time_s"] = time.perf_counter() - started
    return result


def _error_kind_of(tissue: Any, e: BaseException) -> str:
    """A kind for a TissueError without one: ``mesh`` for a MeshError, else ``input``."""
    mesh_error = getattr(tissue, "MeshError", None)
    if mesh_error is not None and isinstance(e, mesh_error):
        return "mesh"
    return "input"


def _worker_init() -> None:
    """The default pool's workers: one planner thread each (a worker per core is the pool's
    parallelism), unless the user set ``RAYON_NUM_THREADS``."""
    os.environ.setdefault("RAYON_NUM_THREADS", "1")


# --------------------------------------------------------------------------------------------
# Executors
# --------------------------------------------------------------------------------------------


class RayExecutor:
    """``submit(fn, *args)`` on a Ray cluster: each call a Ray task, its future a
    ``concurrent.futures.Future`` (``ObjectRef.future()``). ``ray.init(...)`` first (or let
    this call it with ``address``); ``options`` go to ``ray.remote`` (e.g. ``num_cpus=1``)."""

    def __init__(self, address: str | None = None, **options: Any):
        import ray

        if not ray.is_initialized():
            ray.init(address=address)
        self._ray = ray
        self._options = options or {"num_cpus": 1}
        self._remote: dict = {}

    def submit(self, fn: Callable, *args: Any) -> cf.Future:
        remote = self._remote.get(fn)
        if remote is None:
            remote = self._remote[fn] = self._ray.remote(**self._options)(fn)
        return remote.remote(*args).future()

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        pass


def _is_dask_future(f: Any) -> bool:
    return type(f).__module__.split(".")[0] == "distributed"


def _wait_first(pending: set) -> tuple[set, set]:
    """The finished futures of ``pending`` (at least one), and the rest."""
    sample = next(iter(pending))
    if isinstance(sample, cf.Future):
        done, rest = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
        return set(done), set(rest)
    if _is_dask_future(sample):
        import distributed

        done, rest = distributed.wait(list(pending), return_when="FIRST_COMPLETED")
        return set(done), set(rest)
    # Anything else with .done(): poll; without it, take them in turn.
    if hasattr(sample, "done"):
        delay = 0.002
        while True:
            done = {f for f in pending if f.done()}
            if done:
                return done, pending - done
            time.sleep(delay)
            delay = min(delay * 2, 0.1)
    return {sample}, pending - {sample}


def _default_executor(workers: int | None) -> cf.Executor:
    # spawn, not fork: a forked child of a process whose planner has started its thread pool
    # would inherit a pool without threads.
    return cf.ProcessPoolExecutor(
        max_workers=workers or os.cpu_count() or 1,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_worker_init,
    )


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------


def _write_atomic(out_dir: Path, key: str, result: dict) -> Path:
    final = out_dir / f"{key}.json"
    fd, tmp = tempfile.mkstemp(prefix=f".{key}.json.tmp-{os.getpid()}-", dir=out_dir)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(result, f, indent=1, sort_keys=True, ensure_ascii=False)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, final)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return final


def _read_result(out_dir: Path, key: str) -> dict | None:
    path = out_dir / f"{key}.json"
    try:
        with open(path, encoding="utf-8") as f:
            result = json.load(f)
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return None  # unreadable: planned again, and replaced
    if not isinstance(result, dict) or result.get("key") != key:
        return None
    return result


def _row(given: dict, key: str, result: dict | None, error: dict | None = None) -> dict:
    row = dict(given)
    figures = (result or {}).get("figures") or {}
    for name in FIGURES:
        row[name] = figures.get(name)
    err = error if error is not None else (result or {}).get("error")
    row["error"] = None if err is None else f"{err.get('kind')}: {err.get('message')}"
    row["error_kind"] = None if err is None else err.get("kind")
    row["error_field"] = None if err is None else err.get("field")
    row["key"] = key
    return row


def _table(rows: list[dict], as_frame: bool | None) -> Any:
    if as_frame is False:
        return rows
    try:
        import pandas
    except ImportError:
        if as_frame:
            raise
        return rows
    return pandas.DataFrame(rows)


# --------------------------------------------------------------------------------------------
# run
# --------------------------------------------------------------------------------------------


def run(
    cases: Iterable[Mapping] | str | os.PathLike,
    out_dir: str | os.PathLike,
    executor: Any = None,
    *,
    progress: Callable[[int, int], Any] | None = None,
    workers: int | None = None,
    send_files: bool = False,
    max_pending: int = 1000,
    as_frame: bool | None = None,
) -> Any:
    """Plans every case as an independent task on ``executor`` and returns the summary.

    ``cases``: an iterable of dicts (``patient``: a file path or one of :data:`SHIPPED`;
    ``unit`` of a file, default cm; ``vertex`` or ``at``; any ``tissue.plan`` request field),
    or the path of a ``.jsonl``, ``.json`` or ``.csv`` file of them. Relative patient paths are
    resolved against the cases file's folder, or the current folder for an iterable.

    ``out_dir``: created if missing; each case's result is ``<key>.json`` (:func:`case_key`),
    written atomically by this process as results arrive, so workers need no shared file
    system for it. A case whose result is already there is not run again; a case that failed
    is recorded with its error's kind and is not run again either (a worker lost or a pool
    broken is not recorded: a rerun retries it).

    ``executor``: anything with ``submit(fn, *args)`` whose futures have ``.result()``
    (``concurrent.futures`` executors, ``dask.distributed.Client``, :class:`RayExecutor`).
    Default: a local ``ProcessPoolExecutor`` of ``workers`` (default: one per core) processes,
    one planner thread each, created and shut down here.

    ``progress(done, total)`` is called as cases finish (skipped ones count as done at once).
    ``send_files``: send each patient file's bytes with its task (workers without the files).
    At most ``max_pending`` tasks are in flight at once.

    Returns one row per case in input order: its fields as given, :data:`FIGURES`, ``error``
    (None, or ``"kind: message"``), ``error_kind``, ``error_field`` and ``key``; a pandas
    DataFrame when pandas can be imported (``as_frame=None``), else a list of dicts.
    """
    if isinstance(cases, (str, os.PathLike)):
        base = Path(cases).resolve().parent
        given_cases = load_cases(cases)
    else:
        base = Path.cwd()
        given_cases = [dict(c) for c in cases]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    version = _version()
    hashes: dict[str, str] = {}

    total = len(given_cases)
    prepared = [_prepare(c, base, version, hashes) for c in given_cases]
    results: dict[str, dict] = {}
    errors: dict[str, dict] = {}  # not recorded in a file: cases that cannot be sent, lost workers
    to_run: dict[str, _Prepared] = {}
    for p in prepared:
        if p.key in results or p.key in to_run or p.key in errors:
            continue
        if p.error is not None:
            errors[p.key] = {"kind": p.error.kind, "field": p.error.field, "message": p.error.message}
            continue
        existing = _read_result(out, p.key)
        if existing is not None:
            results[p.key] = existing
        else:
            to_run[p.key] = p

    done = total - sum(1 for p in prepared if p.key in to_run)
    if progress is not None:
        progress(done, total)
    waiting_rows = {}  # key -> number of input rows waiting for it
    for p in prepared:
        if p.key in to_run:
            waiting_rows[p.key] = waiting_rows.get(p.key, 0) + 1

    owned = executor is None and to_run
    if owned:
        executor = _default_executor(workers)
    try:
        queue = list(to_run.values())
        queue.reverse()
        pending: dict[Any, _Prepared] = {}
        while queue or pending:
            while queue and len(pending) < max_pending:
                p = queue.pop()
                task = p.task
                assert task is not None
                if send_files and "path" in task:
                    task = dict(task)
                    with open(task["path"], "rb") as f:
                        task["data"] = f.read()
                fut = executor.submit(
                    _run_case, task["case"], task.get("shipped"), task.get("path"), task.get("sha256"), task.get("data")
                )
                pending[fut] = p
            finished, _ = _wait_first(set(pending))
            for fut in finished:
                p = pending.pop(fut)
                try:
                    result = fut.result()
                except Exception as e:  # the worker, not the case: not recorded, a rerun retries
                    errors[p.key] = {"kind": "worker", "field": None, "message": f"{type(e).__name__}: {e}"}
                else:
                    result = dict(result)
                    if result.pop("transient", False):
                        errors[p.key] = result["error"]
                    else:
                        result["key"] = p.key
                        _write_atomic(out, p.key, result)
                        results[p.key] = result
                done += waiting_rows.get(p.key, 1)
                if progress is not None:
                    progress(done, total)
    except BaseException:
        if owned:
            executor.shutdown(wait=False, cancel_futures=True)
            owned = False
        raise
    finally:
        if owned:
            executor.shutdown(wait=True)

    rows = [_row(p.given, p.key, results.get(p.key), errors.get(p.key)) for p in prepared]
    return _table(rows, as_frame)


# --------------------------------------------------------------------------------------------
# python -m tissue.batch
# --------------------------------------------------------------------------------------------


def _format_value(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4f}" if abs(v) < 1e6 else f"{v:.4g}"
    return str(v)


def _print_table(rows: list[dict], stream) -> None:
    if not rows:
        print("no cases", file=stream)
        return
    inputs: list[str] = []
    for r in rows:
        for k in r:
            if k not in FIGURES and k not in ("error", "error_kind", "error_field", "key") and k not in inputs:
                inputs.append(k)
    columns = ["key"] + inputs + ["area_gain_cm2", "volume_difference_cm3", "steps", "error"]
    cells = [[(r["key"][:12] if c == "key" else _format_value(r.get(c))) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(columns)]
    print("  ".join(c.ljust(w) for c, w in zip(columns, widths)).rstrip(), file=stream)
    for row in cells:
        print("  ".join(v.ljust(w) for v, w in zip(row, widths)).rstrip(), file=stream)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tissue.batch",
        description="Plan every case of a cases file (.jsonl, .json or .csv) as an independent task; "
        "each result is written to DIR/<key>.json, and cases already there are skipped.",
        epilog="Exit status: 0 every case ran, 1 some failed (their errors are recorded), 2 usage errors.",
    )
    parser.add_argument("cases", metavar="CASES", help="the cases file: .jsonl, .json (a list) or .csv")
    parser.add_argument("--out", metavar="DIR", required=True, help="the results folder (created if missing)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler's address (tcp://host:8786); default: a local process pool")
    parser.add_argument("--workers", metavar="N", type=int, help="local pool size [default: one per core]")
    parser.add_argument("--send-files", action="store_true", help="send patient files with the tasks (workers without them)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON lines")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args(argv)  # exits 2 on a usage error
    if args.workers is not None and args.workers < 1:
        parser.error("--workers is at least 1")
    if args.scheduler and args.workers:
        parser.error("--workers is for the local pool; a Dask cluster has its own workers")
    try:
        load_cases(args.cases)  # read before any cluster is reached: a bad file is a usage error
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    client = None
    executor = None
    if args.scheduler:
        try:
            from distributed import Client
        except ImportError:
            print("error: --scheduler needs dask.distributed: pip install 'dask[distributed]'", file=sys.stderr)
            return 2
        try:
            client = executor = Client(args.scheduler)
        except Exception as e:
            print(f"error: cannot reach the Dask scheduler {args.scheduler}: {e}", file=sys.stderr)
            return 2

    tty = sys.stderr.isatty()

    def show(done: int, total: int) -> None:
        if args.quiet:
            return
        if tty:
            print(f"\r{done}/{total} cases", end="" if done < total else "\n", file=sys.stderr, flush=True)
        elif done == total:
            print(f"{done}/{total} cases", file=sys.stderr, flush=True)

    try:
        rows = run(
            args.cases,
            args.out,
            executor,
            progress=show,
            workers=args.workers,
            send_files=args.send_files,
            as_frame=False,
        )
    finally:
        if client is not None:
            client.close()
    if args.json:
        for r in rows:
            print(json.dumps(r, sort_keys=True))
    else:
        _print_table(rows, sys.stdout)
    failed = sum(1 for r in rows if r["error"] is not None)
    if failed:
        print(f"{failed} of {len(rows)} cases failed (recorded in {args.out})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    # Run through the package's module, so that tasks pickle as tissue.batch._run_case (not
    # __main__._run_case, which a worker could not import).
    from tissue.batch import main as _main

    sys.exit(_main())
