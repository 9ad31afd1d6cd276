"""Type stubs of `tissue`: the planner and the trainer from Python.

Units: a patient's positions and displacements in its file's unit (``Patient.unit``); request
fields with their units in their names (cm, cm², cm³ = mL, kPa, g/cm³, s, h); trainer positions
in cm (y up), forces in newtons.
"""

from os import PathLike
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np
import numpy.typing as npt

from ._errors import (
    Cancelled as Cancelled,
    InputError as InputError,
    MeshError as MeshError,
    PlanError as PlanError,
    TissueError as TissueError,
    TrainerError as TrainerError,
)

__version__: str
#: The report's schema version (``report["schema_version"]``).
REPORT_SCHEMA_VERSION: int
#: The planner's request fields by JSON name: the keywords of ``plan`` and its siblings.
REQUEST_FIELDS: Tuple[str, ...]

#: ``progress(step, max_steps, settle)``: ``settle`` in [0, 1]; return ``False`` to cancel.
Progress = Callable[[int, int, float], Optional[bool]]
ArrayLike = npt.ArrayLike
Point = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
Quaternion = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
Pose = Tuple[Quaternion, Point]
Path = Union[str, "PathLike[str]"]

class Patient:
    """A patient surface in its file's unit (and, inside, in cm). Immutable."""

    @staticmethod
    def shipped(name: str) -> Patient:
        """``"table2"`` (20 cm plane, 65 × 65 vertices, cm), ``"chest"`` or ``"head"`` (dm)."""
    @staticmethod
    def load(path: Path, unit: str = "cm") -> Patient:
        """A ``.obj``, ``.ply``, ``.stl`` or ``.vtk`` surface in ``unit`` (``"mm"``, ``"cm"``,
        ``"dm"``, ``"m"``). Raises ``InputError`` (missing, unreadable) or ``MeshError``."""
    @staticmethod
    def from_arrays(
        vertices: ArrayLike, triangles: ArrayLike, unit: str = "cm", label: Optional[str] = None
    ) -> Patient:
        """``vertices`` float64 or float32 ``(n, 3)`` in ``unit``; ``triangles`` integer
        ``(m, 3)``, counter-clockwise seen from outside. Raises ``MeshError``."""
    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """``(n, 3)``, in ``unit``; a new array each time."""
    @property
    def triangles(self) -> npt.NDArray[np.int64]:
        """``(m, 3)`` vertex indices."""
    @property
    def unit(self) -> str: ...
    @property
    def cm_per_unit(self) -> float: ...
    @property
    def label(self) -> str: ...
    @property
    def shipped_name(self) -> Optional[str]: ...
    @property
    def suggested_vertex(self) -> Optional[int]:
        """A vertex that runs with the default implant (shipped patients; else ``None``)."""
    def __len__(self) -> int: ...

class Plan:
    """A finished planning job."""

    @property
    def mode(self) -> str:
        """``"single"``, ``"sweep"``, ``"target-gain"`` or ``"expansion"``."""
    @property
    def report(self) -> Dict[str, Any]:
        """The report: the same JSON as ``insert --report`` (``"tool": "python"``)."""
    @property
    def report_json(self) -> str: ...
    @property
    def area_gain_cm2(self) -> Optional[float]:
        """cm²: a single run's, or the target-gain answer's; else ``None``."""
    @property
    def volume_difference_cm3(self) -> Optional[float]:
        """cm³ between the skin before and after (single runs)."""
    @property
    def volume_cm3(self) -> Optional[float]:
        """cm³: a single run's fill, or the target-gain answer."""
    @property
    def vertices_after(self) -> Optional[npt.NDArray[np.float64]]:
        """``(n, 3)`` in the patient's unit (single runs)."""
    @property
    def displacement(self) -> Optional[npt.NDArray[np.float64]]:
        """``(n,)`` in the patient's unit; 0 outside the region (single runs)."""
    @property
    def stretch(self) -> Optional[npt.NDArray[np.float64]]:
        """``(n,)`` area after / area before; 0 outside the region (single runs)."""
    @property
    def in_region(self) -> Optional[npt.NDArray[np.float64]]:
        """``(n,)`` 1.0 in the simulated region, 0.0 outside (single runs)."""

def plan(
    patient: Patient,
    *,
    vertex: Optional[int] = None,
    at: Optional[Point] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """One insertion; ``request``: the planner's request fields by JSON name."""

def sweep(
    patient: Patient,
    volumes_cm3: Iterable[float],
    *,
    vertex: Optional[int] = None,
    at: Optional[Point] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """The insertion at each volume (cm³): ``report["runs"]``, ``report["failed_runs"]``."""

def target_gain(
    patient: Patient,
    gain_cm2: float,
    bracket_cm3: Optional[Tuple[float, float]] = None,
    *,
    gain_tolerance_cm2: Optional[float] = None,
    vertex: Optional[int] = None,
    at: Optional[Point] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """The volume (cm³) that gains ``gain_cm2`` cm²: ``plan.volume_cm3``."""

def expand(
    patient: Patient,
    weeks: int,
    *,
    vertex: Optional[int] = None,
    at: Optional[Point] = None,
    progress: Optional[Progress] = None,
    **request: Any,
) -> Plan:
    """Expansion over ``weeks`` weekly fills: ``report["weeks"]``, ``["flap"]``, ``["band"]``."""

def run_job(
    patient: Patient,
    job: Union[str, Mapping[str, Any]],
    *,
    progress: Optional[Progress] = None,
) -> Plan:
    """A job in the planner's job JSON (``insert --job``, the studio, the C ABI)."""

class Body:
    """A trainee's soft body on its tray (cm, y up; 10 ms steps)."""

    @staticmethod
    def shipped(name: str) -> Body:
        """``"bunny"`` (10 cm), ``"liver"`` (16 cm) or ``"appendix"`` (8 × 2 × 2 cm)."""
    @staticmethod
    def load(path: Path, size_cm: Optional[float] = None) -> Body:
        """A closed surface (filled) or a tet mesh file, in cm, scaled to ``size_cm``."""
    @staticmethod
    def from_mesh(
        vertices: ArrayLike, tets_or_triangles: ArrayLike, cm_per_unit: float = 1.0
    ) -> Body:
        """``(n, 3)`` vertices with ``(m, 4)`` tets or ``(m, 3)`` closed-surface triangles."""
    def step(self, n: int = 1) -> int:
        """``n`` steps of 10 ms with the GIL released; returns the events they added."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """``(n, 3)`` cm."""
    @property
    def triangles(self) -> npt.NDArray[np.int64]:
        """``(m, 3)`` surface triangles (change with cuts and sutures)."""
    @property
    def tets(self) -> npt.NDArray[np.int64]: ...
    @property
    def info(self) -> Dict[str, Any]:
        """``label``, ``nodes``, ``tets``, ``triangles``, ``steps``, ``surface_version``,
        ``volume_drift``, ``step_ms_median``, ``step_ms_p99``, ``time_step_s``, ``tools``,
        ``tray_side_cm``, ``up``, ``self_collision``, ``self_contacts``,
        ``self_contacts_active``."""
    @property
    def self_collision(self) -> bool:
        """Self-collision of the surface (cut walls included); on by default, ``False``
        switches it off (for comparison)."""
    @self_collision.setter
    def self_collision(self, on: bool) -> None: ...
    def self_intersections(self) -> int:
        """Pairs of surface triangles intersecting now, counted exactly."""
    def add_capsule(
        self, a: Point, b: Point, radius: float, pose: Optional[Pose] = None
    ) -> Tool:
        """A capsule tool: within ``radius`` cm of ``a``–``b`` (cm, tool frame), at ``pose``."""
    def add_blade(
        self, a: Point, b: Point, c: Point, thickness: float, pose: Optional[Pose] = None
    ) -> Tool: ...
    def grab(self, point: Point, triangle: Optional[int] = None) -> Dict[str, Any]: ...
    def drag(self, target: Point) -> None: ...
    def release(self) -> None: ...
    @property
    def grasp_force(self) -> npt.NDArray[np.float64]:
        """The tissue's force on the grasp, N, ``(3,)``."""
    def cut(self, path: ArrayLike, view_dir: Point) -> int:
        """Queues a scalpel cut along ``(k, 3)`` points (cm); returns the segments queued."""
    def suture(self, a: Point, b: Point) -> Dict[str, Any]:
        """A suture across a wound: the event (``suture_placed`` or ``suture_missed``)."""
    def play(self) -> None: ...
    def events(self) -> List[Dict[str, Any]]:
        """The events since the last call: ``{"step", "kind", "text"}``."""

class Tool:
    """A contact tool of a body."""

    @property
    def id(self) -> int: ...
    @property
    def pose(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """``(quaternion (x, y, z, w), translation cm)``."""
    @pose.setter
    def pose(self, value: Pose) -> None: ...
    @property
    def force(self) -> npt.NDArray[np.float64]:
        """The tissue's force on the tool, N, ``(3,)``, world axes (y up)."""
