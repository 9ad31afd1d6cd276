"""The trainer through Python: the scalpel and the needle on the appendix, a capsule pressed
into the bunny pushed back up, bodies from arrays and files, and each error's class."""

from __future__ import annotations

import numpy as np
import pytest

import tissue

from conftest import fixture

IDENTITY = (0.0, 0.0, 0.0, 1.0)


def top(body: tissue.Body, x: float, z: float) -> float:
    """The surface's height (y is up) over (x, z): the highest node within 0.3 cm."""
    p = body.positions
    near = np.hypot(p[:, 0] - x, p[:, 2] - z) < 0.3
    return float(p[near, 1].max())


def test_a_cut_across_the_appendix_opens_it_and_a_suture_closes_the_wound() -> None:
    body = tissue.Body.shipped("appendix")
    assert body.info["up"] == "y"
    body.step(20)
    triangles = body.info["triangles"]
    version = body.info["surface_version"]
    # The scalpel drawn across the top at x = 0 (the appendix lies along x), seen from above.
    path = np.array([[0.0, top(body, 0.0, z), z] for z in np.linspace(-1.3, 1.3, 11)])
    segments = body.cut(path, view_dir=(0, -1, 0))
    assert segments >= 2
    body.step(segments + 5)
    kinds = [e["kind"] for e in body.events()]
    assert "cut_advanced" in kinds, kinds
    assert body.info["triangles"] > triangles
    assert body.info["surface_version"] != version
    assert body.triangles.shape == (body.info["triangles"], 3)
    assert body.triangles.max() < body.positions.shape[0]
    # The needle across the wound, 0.3 cm either side of the cut.
    a, b = (-0.3, top(body, -0.3, 0.0), 0.0), (0.3, top(body, 0.3, 0.0), 0.0)
    sutured = body.suture(a, b)
    assert sutured["kind"] == "suture_placed", sutured["text"]
    assert [e["kind"] for e in body.events()] == ["suture_placed"]
    # The same stitch again is refused, naming why.
    with pytest.raises(tissue.TrainerError) as e:
        body.suture(a, b)
    assert e.value.kind == "tool" and "already there" in str(e.value)
    body.step(10)
    assert np.isfinite(body.positions).all()
    assert abs(body.info["volume_drift"]) < 0.1


def test_self_collision_is_on_by_default_and_switched_off_and_on() -> None:
    """Issue 35: on by default, as in the trainer, the studio and the C ABI; the wound's walls
    of a fresh cut are held by self-contacts; switched off (for comparison) there are none, and
    switched on again they are held again."""
    body = tissue.Body.shipped("appendix")
    assert body.self_collision is True and body.info["self_collision"] is True
    body.step(20)
    assert body.self_intersections() == 0
    path = np.array([[0.0, top(body, 0.0, z), z] for z in np.linspace(-1.3, 1.3, 11)])
    body.step(body.cut(path, view_dir=(0, -1, 0)) + 5)
    assert body.info["self_contacts"] > 0, body.info
    body.self_collision = False
    body.step()
    assert body.self_collision is False and body.info["self_collision"] is False
    assert body.info["self_contacts"] == 0 and body.info["self_contacts_active"] == 0
    assert body.self_intersections() >= 0
    body.self_collision = True
    body.step()
    assert body.self_collision is True and body.info["self_collision"] is True
    assert body.info["self_contacts"] > 0, body.info


def test_a_capsule_pressed_down_into_the_bunny_is_pushed_up() -> None:
    body = tissue.Body.shipped("bunny")
    body.step(30)
    p = body.positions
    assert p[:, 1].min() >= -0.05, "the organ lies on the tray, y = 0 its top"
    # Over the bunny's middle, where it is thick.
    cx, cz = float(np.median(p[:, 0])), float(np.median(p[:, 2]))
    y0 = top(body, cx, cz)
    # A vertical capsule, its tip's centre at the pose's origin, from 1 cm above the surface
    # down to 1 cm into it over 20 steps (10 ms each), then held.
    probe = body.add_capsule([0, 0, 0], [0, 3, 0], 0.4, pose=(IDENTITY, (cx, y0 + 1.0, cz)))
    assert probe.id == 0 and body.info["tools"] == 1
    np.testing.assert_allclose(probe.pose[1], [cx, y0 + 1.0, cz], rtol=1e-6)
    forces = []
    for i in range(40):
        y = y0 + 1.0 - 2.0 * min(i, 20) / 20
        probe.pose = (IDENTITY, (cx, y, cz))
        body.step()
        forces.append(probe.force)
    f = forces[-1]
    assert f.shape == (3,) and f.dtype == np.float64
    # The tissue pushes the probe back up (y up), in newtons: a soft organ, well under 100 N.
    assert f[1] > 0, f
    assert 1e-4 < np.linalg.norm(f) < 100, f
    assert abs(f[1]) > max(abs(f[0]), abs(f[2])), f
    # Before it touched, nothing.
    assert np.linalg.norm(forces[0]) < 1e-6


def test_grab_drag_release_report_their_events() -> None:
    body = tissue.Body.shipped("appendix")
    body.step(5)
    tip = (3.8, top(body, 3.8, 0.0), 0.0)
    grabbed = body.grab(tip)
    assert grabbed["kind"] == "grabbed"
    body.drag((3.8, tip[1] + 1.0, 0.0))
    body.step(10)
    assert body.grasp_force[1] < 0, "the tissue pulls the lifted grasp down"
    body.release()
    assert [e["kind"] for e in body.events()] == ["grabbed", "released"]


def test_bodies_from_arrays_files_and_sizes(tmp_path) -> None:
    # A tet box from arrays: 2 × 2 × 2 cm of 6-tet cubes.
    n = 3
    grid = np.stack(np.meshgrid(*[np.linspace(-1, 1, n)] * 3, indexing="ij"), -1).reshape(-1, 3)
    at = lambda i, j, k: (i * n + j) * n + k  # noqa: E731
    tets = []
    for i in range(n - 1):
        for j in range(n - 1):
            for k in range(n - 1):
                c = [at(i + a, j + b, k + d) for a in (0, 1) for b in (0, 1) for d in (0, 1)]
                # Kuhn's six tets of a cube, positively oriented.
                for t in ((0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)):
                    tets.append([c[t[0]], c[t[1]], c[t[2]], c[t[3]]])
    tets = np.array(tets)
    a = grid[tets[:, 1]] - grid[tets[:, 0]]
    b = grid[tets[:, 2]] - grid[tets[:, 0]]
    c = grid[tets[:, 3]] - grid[tets[:, 0]]
    flip = np.einsum("ij,ij->i", np.cross(a, b), c) < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    box = tissue.Body.from_mesh(grid, tets, cm_per_unit=2.0)
    assert box.info["tets"] == len(tets)
    extent = box.positions.max(axis=0) - box.positions.min(axis=0)
    np.testing.assert_allclose(extent, [4.0, 4.0, 4.0], rtol=1e-5)
    box.step(3)
    # A closed surface from a file, filled with tetrahedra, scaled as `trainer --size`.
    bunny = tissue.Body.load(fixture("bunny_10k.obj"), size_cm=5.0)
    extent = bunny.positions.max(axis=0) - bunny.positions.min(axis=0)
    assert extent.max() == pytest.approx(5.0, rel=1e-4)
    assert bunny.info["tets"] > 100


def test_trainer_errors_have_their_classes(tmp_path) -> None:
    with pytest.raises(tissue.InputError) as e:
        tissue.Body.load(tmp_path / "missing.obj")
    assert isinstance(e.value, OSError) and e.value.field == "path"
    with pytest.raises(tissue.MeshError):
        tissue.Body.from_mesh(np.zeros((4, 2)), np.array([[0, 1, 2, 3]]))
    with pytest.raises(tissue.MeshError):
        # An open surface cannot be filled.
        tissue.Body.from_mesh(np.eye(3), np.array([[0, 1, 2]]))
    with pytest.raises(tissue.TrainerError) as e:
        tissue.Body.shipped("spleen")
    assert e.value.field == "name"
    body = tissue.Body.shipped("appendix")
    with pytest.raises(tissue.TrainerError) as e:
        body.cut([[0, 2, 0]], view_dir=(0, -1, 0))
    assert e.value.kind == "tool"
    with pytest.raises(tissue.TrainerError):
        body.grab((500.0, 0.0, 0.0))
    with pytest.raises(tissue.MeshError):
        body.add_capsule([0, 0, 0], [0, 1, 0], 0.2, pose=((0, 0, 0, 2), (0, 5, 0)))
    with pytest.raises(tissue.TissueError):
        body.add_capsule([0, 0, 0], [0, 1, 0], -1.0)
