"""tissue: soft-tissue surgery planning and a PBD surgical trainer, from Python.

Planning (the same front door as ``insert``, the studio and the C ABI; the reports are the
same JSON as ``insert --report``, with ``"tool": "python"``)::

    import tissue
    patient = tissue.Patient.shipped("table2")          # or .load(path, unit=) / .from_arrays
    plan = tissue.plan(patient)                          # Table 2: 100 cm³, 7 cm round
    plan.area_gain_cm2, plan.volume_difference_cm3       # cm², cm³
    plan.vertices_after, plan.displacement               # (n, 3), (n,) in the patient's unit
    plan.report                                          # dict: the JSON report

    tissue.sweep(patient, [50, 100, 150])                # .report["runs"]
    tissue.target_gain(patient, 30.0, bracket_cm3=(40, 200))
    tissue.expand(patient, 4, volume_cm3=200)            # .report["weeks"], ["band"]

Every keyword of a request is a field of the planner's request, by its JSON name with its
unit (``volume_cm3``, ``diameter_cm``, ``depth_cm``, ``sim_edge_cm``, ``young_kpa``, …; see
:data:`REQUEST_FIELDS`); an unknown name raises :class:`PlanError` naming it (``.field``).
Runs release the GIL; ``progress(step, max_steps, settle)`` is called on the calling thread
about every 20 ms and may return ``False`` to cancel (:class:`Cancelled`); Ctrl-C cancels a
run and raises ``KeyboardInterrupt`` within about 20 ms.

The trainer (cm, y up, forces in newtons)::

    body = tissue.Body.shipped("appendix")               # or "bunny", "liver", .load, .from_mesh
    body.step(20)
    probe = body.add_capsule([0, 0, 0], [0, 3, 0], 0.3, pose=((0, 0, 0, 1), (1.5, 2.6, 0)))
    probe.pose = ((0, 0, 0, 1), (1.5, 1.9, 0)); body.step(); probe.force   # N, (3,)
    body.cut(path, view_dir=(0, -1, 0)); body.suture(a, b); body.events()

Errors are subclasses of :class:`TissueError`: :class:`PlanError` (``.kind``, ``.field``),
:class:`Cancelled`, :class:`MeshError` (also a ``ValueError``), :class:`InputError` (also an
``OSError``), :class:`TrainerError`.
"""

from __future__ import annotations

import json
import math
from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

from ._errors import (
    Cancelled,
    InputError,
    MeshError,
    PlanError,
    TissueError,
    TrainerError,
)
from ._tissue import (
    REPORT_SCHEMA_VERSION,
    Body,
    Patient,
    Plan,
    Tool,
    __version__,
    _request_fields,
    _run,
)

__all__ = [
    "__version__",
    "REPORT_SCHEMA_VERSION",
    "REQUEST_FIELDS",
    "Patient",
    "Plan",
    "plan",
    "sweep",
    "target_gain",
    "expand",
    "run_job",
    "Body",
    "Tool",
    "TissueError",
    "PlanError",
    "Cancelled",
    "MeshError",
    "InputError",
    "TrainerError",
]

#: The planner's request fields (``PlanRequest``'s JSON names, units in the names): the
#: keywords ``plan``, ``sweep``, ``target_gain`` and ``expand`` take.
REQUEST_FIELDS: Tuple[str, ...] = tuple(_request_fields())

Progress = Callable[[int, int, float], Optional[bool]]


def _plain(name: str, value: Any) -> Any:
    """``value`` as plain JSON data (NumPy arrays and scalars to lists and numbers), or a
    :class:`PlanError` naming ``name``."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    elif isinstance(value, (tuple, list)):
        value = [_plain(name, v) for v in value]
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise PlanError(
            f"`{name}` cannot be given as {value!r}: {e}", kind="usage", field=name
        ) from None
    if isinstance(value, float) and not math.isfinite(value):  # pragma: no cover
        raise PlanError(f"`{name}` must be finite", kind="usage", field=name)
    return value


def _request(vertex: Any, at: Any, request: Mapping[str, Any]) -> Dict[str, Any]:
    """The request's JSON object: ``None`` values are left out (the library's default)."""
    out: Dict[str, Any] = {}
    for name, value in (("vertex", vertex), ("at", at), *request.items()):
        if value is not None:
            out[name] = _plain(name, value)
    return out


def run_job(
    patient: Patient,
    job: Union[str, Mapping[str, Any]],
    *,
    progress: Optional[Progress] = None,
) -> Plan:
    """Runs a planning job given as the planner's job JSON (a dict or its text):
    ``{"mode": "single" | "sweep" | "target-gain" | "expansion", "request": {...},
    "volumes_cm3": [...], "target_gain_cm2": 30, "bracket_cm3": [lo, hi],
    "gain_tolerance_cm2": 0.5}`` (what ``insert --job``, the studio and the C ABI take; the
    files ``fixtures/reports/*.job.json``). Returns its :class:`Plan`."""
    text = job if isinstance(job, str) else json.dumps(_plain("job", dict(job)))
    return _run(patient, text, progress)


def plan(
    patient: Patient,
    *,
    vertex: Optional[int] = None,
    at: Optional[Sequence[float]] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """Plans one implant insertion on ``patient`` and returns its :class:`Plan`.

    ``vertex`` (an index into ``patient.vertices``) or ``at`` (a point in the patient's unit,
    snapped to the surface) places the implant; the Table 2 plane defaults to its centre, the
    shipped chest and head to their suggested vertex. ``request`` takes the planner's request
    fields by their JSON names (:data:`REQUEST_FIELDS`): ``shape`` (``"round"``,
    ``"rectangular"``, ``"crescent"``), ``diameter_cm``, ``length_cm``, ``width_cm``,
    ``volume_cm3`` (cm³ = mL), ``depth_cm``, ``sim_edge_cm``, ``young_kpa``, ``solver``
    (``"explicit"`` or ``"quasi_static"``), ``max_steps``, …; every one defaults to the
    library's value (no keyword at all is the Table 2 case).

    ``progress(step, max_steps, settle)`` is called on this thread about every 20 ms while
    the run steps (``settle`` 0 to 1: how close to its stop criterion); returning ``False``
    cancels the run (raises :class:`Cancelled`).

    Raises :class:`PlanError` (``.kind``, ``.field``) for a request that cannot run,
    :class:`Cancelled`, or ``KeyboardInterrupt`` on Ctrl-C (the run is cancelled).
    """
    body = {"mode": "single", "request": _request(vertex, at, request)}
    return _run(patient, json.dumps(body), progress)


def sweep(
    patient: Patient,
    volumes_cm3: Iterable[float],
    *,
    vertex: Optional[int] = None,
    at: Optional[Sequence[float]] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """The insertion of ``request`` at each of ``volumes_cm3`` (cm³; 1 to 64 of them, run in
    parallel). The rows are ``plan.report["runs"]`` (one per volume that ran, in order) and
    ``plan.report["failed_runs"]`` (a volume the implant's base cannot hold, with its error);
    the sweep fails as a whole only when no run ran. Arguments as :func:`plan`."""
    body = {
        "mode": "sweep",
        "request": _request(vertex, at, request),
        "volumes_cm3": _plain("volumes_cm3", list(volumes_cm3)),
    }
    return _run(patient, json.dumps(body), progress)


def target_gain(
    patient: Patient,
    gain_cm2: float,
    bracket_cm3: Optional[Tuple[float, float]] = None,
    *,
    gain_tolerance_cm2: Optional[float] = None,
    vertex: Optional[int] = None,
    at: Optional[Sequence[float]] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """The fill volume at which the insertion of ``request`` gains ``gain_cm2`` cm² of skin,
    searched in ``bracket_cm3`` ``(lo, hi)`` (default: a quarter to twice ``volume_cm3``) to
    within ``gain_tolerance_cm2`` (default: the library's). ``plan.volume_cm3`` is the answer,
    ``plan.area_gain_cm2`` its run's gain, ``plan.report["runs"]`` the runs it took and
    ``plan.report["converged"]`` whether a stopping rule was met. Arguments as :func:`plan`."""
    body: Dict[str, Any] = {
        "mode": "target-gain",
        "request": _request(vertex, at, request),
        "target_gain_cm2": _plain("target_gain_cm2", gain_cm2),
    }
    if bracket_cm3 is not None:
        body["bracket_cm3"] = _plain("bracket_cm3", list(bracket_cm3))
    if gain_tolerance_cm2 is not None:
        body["gain_tolerance_cm2"] = _plain("gain_tolerance_cm2", gain_tolerance_cm2)
    return _run(patient, json.dumps(body), progress)


def expand(
    patient: Patient,
    weeks: int,
    *,
    vertex: Optional[int] = None,
    at: Optional[Sequence[float]] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """Tissue expansion over ``weeks`` weekly fills to ``volume_cm3``, with skin growth: the
    weekly table is ``plan.report["weeks"]`` (and ``["days"]``), the flap ``["flap"]``, the
    uncertainty band ``["band"]`` (``band_samples``, ``band_seed``). The expansion's own
    fields (``hold_weeks``, ``leakage``, ``overfill``, ``growth_step_h``) go in ``request``.
    Arguments as :func:`plan`."""
    body = {
        "mode": "expansion",
        "request": {**_request(vertex, at, request), "expand_weeks": _plain("weeks", weeks)},
    }
    return _run(patient, json.dumps(body), progress)


def __getattr__(name: str) -> Any:
    # `tissue.batch` (population-scale studies on Dask) is imported on first use, so that
    # `import tissue` does not need Dask.
    if name == "batch":
        import importlib

        return importlib.import_module(".batch", __name__)
    raise AttributeError(f"module 'tissue' has no attribute {name!r}")
