"""The package's exceptions: every error the library raises is a :class:`TissueError`.

Each carries ``kind`` (what kind of failure, the library's snake_case name: for planning
``usage``, ``input``, ``mesh``, ``placement``, ``parameters``, ``run``, ``output``,
``cancelled``; for the trainer ``input``, ``mesh``, ``meshing``, ``too_large``,
``parameters``, ``tool``, ``simulation``) and ``field`` (the request field or argument at
fault, or ``None``). The message says what was wrong and what to change.
"""

from __future__ import annotations

from typing import Optional

__all__ = [
    "TissueError",
    "PlanError",
    "Cancelled",
    "MeshError",
    "InputError",
    "TrainerError",
]


class TissueError(Exception):
    """Any error of the library. ``kind`` and ``field`` as the module says."""

    def __init__(
        self, message: str, kind: Optional[str] = None, field: Optional[str] = None
    ) -> None:
        super().__init__(message)
        self.message = message
        self.kind = kind
        self.field = field


class PlanError(TissueError):
    """A planning request that cannot be carried out: ``kind`` is the planner's error kind
    (``usage``, ``placement``, ``parameters``, ``run``, ``output``, ``cancelled``), ``field``
    the request field at fault (its JSON name, e.g. ``"volume_cm3"``) or ``None``."""


class Cancelled(PlanError):
    """The run was cancelled (``progress`` returned ``False``); ``kind`` is ``"cancelled"``.
    Ctrl-C raises ``KeyboardInterrupt`` instead, after cancelling the run."""


class MeshError(TissueError, ValueError):
    """A mesh or array that is not valid: a malformed file, an invalid surface or tet mesh, an
    array of the wrong shape or type (``field`` names the argument)."""


class InputError(MeshError, OSError):
    """A mesh file that is missing, unreadable or of an unsupported type (``kind``
    ``"input"``)."""


class TrainerError(TissueError):
    """A trainer action or body that cannot be done: ``kind`` ``tool`` (a grab off the
    surface, a cut too short, …), ``parameters`` or ``simulation`` (a diverged step, a failed
    cut)."""
