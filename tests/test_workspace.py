"""Reachability maps and base placement (kinengine.workspace): the orientation set, the reach bound, every
reached flag against the closed-form and numeric solvers, determinism, Zarr stores and resuming, a Dask
LocalCluster (bit for bit, and with a worker killed), base placement on a task with a known base."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

import kinengine
from kinengine import OptionError
from kinengine.workspace import ReachabilityMap, base_placements, orientation_set, reachability_map
from kinengine.workspace.grid import VoxelGrid, reach_ball
from kinengine.workspace.orientations import fibonacci_directions, nearest_orientation

pytest.importorskip("eaik", reason="the closed-form solver needs the ik extra")


def _ball(robot):
    model = robot.pinocchio_model()
    return reach_ball(
        model, robot.frame_id(robot.end_effector), model.lowerPositionLimit, model.upperPositionLimit
    )


@pytest.fixture(scope="module")
def abb_map(abb):
    return reachability_map(abb, voxel=0.1, orientations=12, progress=False)


# -- orientations ---------------------------------------------------------------------------------
@pytest.mark.parametrize("spec, count", [(1, 1), (50, 50), ((10, 4), 40), ((1, 1), 1)])
def test_orientation_set_is_rotations_along_fibonacci_directions(spec, count):
    R = orientation_set(spec)
    assert R.shape == (count, 3, 3)
    np.testing.assert_allclose(
        np.einsum("kji,kjl->kil", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-14
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
    n = spec if isinstance(spec, int) else spec[0]
    rolls = 1 if isinstance(spec, int) else spec[1]
    np.testing.assert_allclose(R[:, :, 2], np.repeat(fibonacci_directions(n), rolls, axis=0), atol=1e-15)
    np.testing.assert_array_equal(R, orientation_set(spec))  # deterministic, bit for bit


def test_fibonacci_directions_cover_the_sphere_evenly():
    d = fibonacci_directions(500)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-15)
    assert np.abs(d.mean(axis=0)).max() < 2e-3  # balanced
    # nearest-neighbour angles within a factor 2 of each other (no clusters, no holes)
    cos = np.clip(d @ d.T - 2 * np.eye(len(d)), -1, 1)
    nearest = np.arccos(cos.max(axis=1))
    assert nearest.max() < 2.0 * nearest.min()


def test_rolls_of_one_direction_are_even():
    R = orientation_set((3, 8))
    x0, x1 = R[0, :, 0], R[1, :, 0]
    assert np.isclose(np.arccos(np.clip(x0 @ x1, -1, 1)), 2 * np.pi / 8)


def test_nearest_orientation_finds_each_member():
    R = orientation_set(40)
    np.testing.assert_array_equal(nearest_orientation(R, R), np.arange(40))


@pytest.mark.parametrize(
    "bad", [0, -3, True, (0, 2), np.ones((2, 3, 3)), np.full((1, 3, 3), np.nan), "50", 10**6]
)
def test_bad_orientations_are_refused(bad):
    with pytest.raises(OptionError, match="orientations|directions|rotation"):
        orientation_set(bad)


# -- reach bound and grid -------------------------------------------------------------------------
def test_reach_ball_of_the_abb_is_its_stretched_arm(abb):
    ball = _ball(abb)
    np.testing.assert_allclose(ball.center, [0.0, 0.0, 0.29], atol=1e-15)
    # joint 2 -> joint 3 (0.27), joint 3 -> wrist centre (|(0.302, 0, 0.07)|), wrist centre -> tool0 (0.072)
    assert ball.radius == pytest.approx(0.27 + np.hypot(0.302, 0.07) + 0.072, abs=1e-12)


@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda_arm", "scara", "planar_3dof"])
def test_no_configuration_leaves_the_reach_ball(name):
    robot = kinengine.load(name)
    ball = _ball(robot)
    Q = robot.random_configuration(rng=1, size=20_000)
    p = robot.frame_pose(Q)[:, :3, 3]
    assert np.linalg.norm(p - ball.center, axis=1).max() <= ball.radius + 1e-12


def test_voxel_lookup_finds_each_centre_and_nothing_outside(abb):
    grid = VoxelGrid.build(_ball(abb), 0.05, None)
    np.testing.assert_array_equal(grid.lookup(grid.centers), np.arange(len(grid.centers)))
    offsets = (np.random.default_rng(0).random((len(grid.centers), 3)) - 0.5) * 0.05 * 0.999
    np.testing.assert_array_equal(grid.lookup(grid.centers + offsets), np.arange(len(grid.centers)))
    assert grid.lookup(np.array([[5.0, 0.0, 0.0], [np.nan, 0, 0]])).tolist() == [-1, -1]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"voxel": 0.0}, "voxel"),
        ({"voxel": float("nan")}, "voxel"),
        ({"voxel": 1e-5}, "cells"),
        ({"bounds": [[0, 0, 0], [0, 1, 1]]}, "bounds"),
        ({"bounds": "box"}, "bounds"),
        ({"method": "fast"}, "method"),
        ({"progress": "yes"}, "progress"),
    ],
)
def test_bad_arguments_are_refused(abb, kwargs, match):
    with pytest.raises(OptionError, match=match):
        reachability_map(abb, **{"voxel": 0.2, "orientations": 2, "progress": False, **kwargs})


def test_closed_form_on_a_chain_without_one_names_the_reason():
    with pytest.raises(OptionError, match="closed_form"):
        reachability_map(
            kinengine.load("panda_arm"), voxel=0.3, orientations=2, method="closed_form", progress=False
        )


# -- the map's values -----------------------------------------------------------------------------
def test_every_cell_agrees_with_the_closed_form_solver(abb, abb_map):
    assert abb_map.metadata["method"] == "closed_form"
    from kinengine.workspace.solve import poses

    T = poses(abb_map.centers, abb_map.orientations)
    sol = abb.ik_solutions(T)
    np.testing.assert_array_equal(abb_map.reached.ravel(), np.asarray(sol.count) > 0)
    assert 0.1 < abb_map.index.mean() < 0.9  # a real workspace: neither empty nor full
    # every reached pose's solutions reproduce it (forward kinematics) within the limits
    q = sol.q[np.asarray(sol.count) > 0][:, 0]
    np.testing.assert_allclose(abb.frame_pose(q), T[np.asarray(sol.count) > 0], atol=1e-9)
    assert np.all((q >= abb.lower_limits) & (q <= abb.upper_limits))


def test_manipulability_is_the_best_over_every_solution(abb, abb_map):
    from kinengine.workspace.solve import poses

    rng = np.random.default_rng(3)
    for v in rng.choice(np.flatnonzero(abb_map.index > 0), 5, replace=False):
        sol = abb.ik_solutions(poses(abb_map.centers[v : v + 1], abb_map.orientations))
        q = sol.q[~np.isnan(sol.q[..., 0])]
        w = [np.sqrt(np.linalg.det(J @ J.T)) for J in abb.jacobian(q)]
        assert abb_map.manipulability[v] == pytest.approx(max(w), rel=1e-9)
    assert np.all(abb_map.manipulability[abb_map.index == 0] == 0.0)


def test_unreached_cells_stay_unreached_for_the_numeric_solver(abb, abb_map):
    from kinengine.workspace.solve import poses

    T = poses(abb_map.centers, abb_map.orientations)[~abb_map.reached.ravel()]
    sample = T[np.random.default_rng(0).choice(len(T), 500, replace=False)]
    res = abb.inverse_kinematics(sample, method="numeric", restarts=20, rng=0)
    assert np.mean(~np.asarray(res.success)) >= 0.99


def test_numeric_map_of_the_panda_agrees_with_more_restarts():
    panda = kinengine.load("panda_arm")
    rmap = reachability_map(panda, voxel=0.25, orientations=6, progress=False)
    assert rmap.metadata["method"] == "numeric"
    from kinengine.workspace.solve import poses

    T = poses(rmap.centers, rmap.orientations)
    reached = T[rmap.reached.ravel()]
    res = panda.inverse_kinematics(reached, method="numeric", restarts=20, rng=1)
    assert np.all(res.success)  # a reached flag is a real solution
    unreached = T[~rmap.reached.ravel()]
    sample = unreached[
        np.random.default_rng(0).choice(len(unreached), min(300, len(unreached)), replace=False)
    ]
    res = panda.inverse_kinematics(sample, method="numeric", restarts=20, rng=2)
    assert np.mean(~np.asarray(res.success)) >= 0.99


def test_a_numeric_chunk_that_reaches_nothing_is_all_unreached():
    """Voxels inside the Panda's reach ball (radius 1.02 m about the shoulder) but beyond its arm (0.95 m):
    the position check reaches none of them, and the chunk is solved without a pose."""
    panda = kinengine.load("panda_arm")
    rmap = reachability_map(
        panda, voxel=0.02, orientations=3, bounds=[[0.98, -0.02, 0.32], [1.0, 0.02, 0.35]], progress=False
    )
    assert rmap.metadata["method"] == "numeric" and len(rmap.centers) > 0
    assert not rmap.reached.any() and np.all(rmap.manipulability == 0.0)


def test_reachable_looks_up_the_cells(abb_map):
    from kinengine.workspace.solve import poses

    T = poses(abb_map.centers, abb_map.orientations)
    np.testing.assert_array_equal(abb_map.reachable(T), abb_map.reached.ravel())
    assert abb_map.reachable(T[0]) == bool(abb_map.reached[0, 0])
    far = np.eye(4)
    far[:3, 3] = 10.0
    assert abb_map.reachable(far) is False


def test_slice_and_plot(abb_map, tmp_path):
    centers, index = abb_map.slice(0.3)
    assert len(centers) and np.all(np.abs(centers[:, 2] - 0.3) <= abb_map.voxel / 2)
    assert len(index) == len(centers)
    abb_map.plot(z=0.3, path=tmp_path / "slice.png")
    assert (tmp_path / "slice.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# -- determinism, stores, resuming ----------------------------------------------------------------
def test_same_arguments_give_the_same_map_bit_for_bit(abb, abb_map):
    again = reachability_map(abb, voxel=0.1, orientations=12, progress=False)
    np.testing.assert_array_equal(again.reached, abb_map.reached)
    np.testing.assert_array_equal(again.manipulability, abb_map.manipulability)
    np.testing.assert_array_equal(again.centers, abb_map.centers)


def test_store_run_equals_memory_run_and_loads_back(abb, abb_map, tmp_path):
    pytest.importorskip("zarr")
    stored = reachability_map(abb, voxel=0.1, orientations=12, store=str(tmp_path / "m.zarr"), progress=False)
    np.testing.assert_array_equal(stored.reached, abb_map.reached)
    loaded = ReachabilityMap.load(tmp_path / "m.zarr")
    np.testing.assert_array_equal(loaded.reached, abb_map.reached)
    np.testing.assert_array_equal(loaded.manipulability, abb_map.manipulability)
    abb_map.save(tmp_path / "m.npz")
    back = ReachabilityMap.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(back.reached, abb_map.reached)
    assert back.metadata == abb_map.metadata


def test_interrupted_run_resumes_only_the_missing_chunks(abb, tmp_path, monkeypatch):
    pytest.importorskip("zarr")
    from kinengine.workspace import reachability

    monkeypatch.setattr(reachability, "POSES_PER_CHUNK", 600)  # ~20 chunks of this small map
    store = str(tmp_path / "r.zarr")
    full = reachability_map(abb, voxel=0.1, orientations=12, progress=False)

    def stop_after_5(done, total):
        if done >= 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        reachability_map(abb, voxel=0.1, orientations=12, store=store, progress=stop_after_5)
    with pytest.raises(OptionError, match="unfinished"):
        ReachabilityMap.load(store)
    resumed = reachability_map(abb, voxel=0.1, orientations=12, store=store, progress=False)
    total = resumed.stats["chunks"]
    assert total >= 10
    assert resumed.stats["resumed"] >= 5 and resumed.stats["computed"] == total - resumed.stats["resumed"]
    np.testing.assert_array_equal(resumed.reached, full.reached)
    np.testing.assert_array_equal(resumed.manipulability, full.manipulability)


def test_a_store_of_another_map_is_refused(abb, tmp_path):
    pytest.importorskip("zarr")
    store = str(tmp_path / "a.zarr")
    reachability_map(abb, voxel=0.2, orientations=4, store=store, progress=False)
    with pytest.raises(OptionError, match="another map"):
        reachability_map(abb, voxel=0.2, orientations=5, store=store, progress=False)


# -- a Dask cluster ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
        ) as c,
        distributed.Client(c) as client,
    ):
        yield client


@pytest.mark.slow
def test_cluster_map_equals_the_local_map(abb, abb_map, cluster, tmp_path):
    rmap = reachability_map(
        abb, voxel=0.1, orientations=12, store=str(tmp_path / "c.zarr"), client=cluster, progress=False
    )
    np.testing.assert_array_equal(rmap.reached, abb_map.reached)
    np.testing.assert_array_equal(rmap.manipulability, abb_map.manipulability)


@pytest.mark.slow
def test_cluster_run_survives_a_killed_worker(abb, abb_map, cluster, tmp_path, monkeypatch):
    from kinengine.workspace import reachability

    monkeypatch.setattr(reachability, "POSES_PER_CHUNK", 300)
    killed = []

    def kill_one_worker(done, total):
        if done == 2 and not killed:
            pids = cluster.run(os.getpid)
            victim = sorted(pids.values())[0]
            killed.append(victim)
            threading.Thread(target=os.kill, args=(victim, 9)).start()

    rmap = reachability_map(
        abb,
        voxel=0.1,
        orientations=12,
        store=str(tmp_path / "k.zarr"),
        client=cluster,
        progress=kill_one_worker,
    )
    assert killed
    np.testing.assert_array_equal(rmap.reached, abb_map.reached)
    np.testing.assert_array_equal(rmap.manipulability, abb_map.manipulability)


def test_a_cluster_run_needs_a_store(abb):
    with pytest.raises(OptionError, match="store"):
        reachability_map(abb, voxel=0.3, orientations=2, client=object(), progress=False)


# -- base placement ---------------------------------------------------------------------------------
def test_base_placement_finds_the_base_the_task_was_made_with(abb):
    rmap = reachability_map(abb, voxel=0.05, orientations=30, progress=False)
    base = np.eye(4)
    yaw = np.pi / 2
    base[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    base[:3, 3] = [1.0, 0.5, 0.0]
    Q = abb.random_configuration(rng=4, size=40)
    targets = base @ abb.frame_pose(Q)
    result = base_placements(rmap, targets, xy=0.1, yaws=8, z=0.0, top=10)
    [true] = [i for i in range(len(result.poses)) if np.allclose(result.poses[i], base, atol=1e-12)]
    assert true in np.argsort(-result.scores, kind="stable")[:10], "the task's own base is a top candidate"
    assert result.verified[true] == len(targets)  # re-checked by IK: it solves every task pose
    assert result.verified[result.order[0]] == len(targets)
    np.testing.assert_allclose(result.best[:3, 3], base[:3, 3], atol=0.25)


def test_base_placement_for_one_task_pose_picks_a_base_ik_verifies(abb):
    """One task pose ties thousands of candidates at score 1; the tie is broken by the voxel's
    reachability index, so the re-checked ones (and the best) reach the pose by IK."""
    rmap = reachability_map(abb, voxel=0.05, orientations=30, progress=False)
    for seed in range(4):
        T = abb.frame_pose(abb.random_configuration(rng=seed))
        result = base_placements(rmap, T[None], yaws=16)
        best = result.order[0]
        assert result.verified[best] == 1
        assert result.depth[best] == pytest.approx(
            rmap.index[rmap.grid.lookup((np.linalg.inv(result.best) @ T)[None, :3, 3])[0]]
        )
        assert abb.ik_solutions(np.linalg.inv(result.best) @ T).reachable


def test_base_placement_warns_when_no_candidate_is_verified(abb_map, abb):
    T = abb.frame_pose(abb.neutral())  # the only candidate base stands 10 m above it: out of reach
    with pytest.warns(UserWarning, match="none of the 1 best-scored base poses reaches a task pose by IK"):
        result = base_placements(abb_map, T[None], xy=[[0.0, 0.0]], yaws=[0.0], z=10.0, top=1)
    assert result.verified.max() == 0


def test_maps_compare_equal_by_value_and_refuse_non_rotations(abb_map, tmp_path):
    abb_map.save(tmp_path / "m.npz")
    again = ReachabilityMap.load(tmp_path / "m.npz")
    assert again == abb_map and again is not abb_map
    other = ReachabilityMap.load(tmp_path / "m.npz")
    object.__setattr__(other, "reached", ~other.reached)
    assert other != abb_map
    with pytest.raises(OptionError, match="not a rotation matrix"):
        abb_map.reachable(2 * np.eye(4))
    with pytest.raises(OptionError, match="cannot write the reachability map to .*nonexistent"):
        abb_map.save(tmp_path / "nonexistent" / "x.npz")


def test_base_placement_arguments_are_checked(abb_map):
    with pytest.raises(OptionError, match="targets"):
        base_placements(abb_map, np.eye(3))
    with pytest.raises(OptionError, match="xy"):
        base_placements(abb_map, np.eye(4), xy=-1.0)
    with pytest.raises(OptionError, match="yaws"):
        base_placements(abb_map, np.eye(4), yaws=0)


# -- command line -----------------------------------------------------------------------------------
def test_cli_reach_and_place(tmp_path, capsys, abb):
    pytest.importorskip("zarr")
    from kinengine.cli.main import main

    store = str(tmp_path / "cli.zarr")
    assert (
        main(
            [
                "reach",
                "abb_irb120",
                "--voxel",
                "0.15",
                "--orientations",
                "6",
                "-o",
                store,
                "--png",
                str(tmp_path / "s.png"),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "closed_form" in out and "written to" in out
    assert (tmp_path / "s.png").exists()
    targets = abb.frame_pose(abb.random_configuration(rng=0, size=5))
    np.save(tmp_path / "t.npy", targets)
    assert main(["place", store, "--targets", str(tmp_path / "t.npy"), "--top", "3"]) == 0
    out = capsys.readouterr().out
    assert "IK-verified" in out and len(out.splitlines()) == 5
    assert main(["place", store, "--targets", str(tmp_path / "missing.npy")]) == 2
    assert "cannot read task poses" in capsys.readouterr().err


def test_bad_maps_and_poses_are_clear_errors(abb_map, tmp_path):
    with pytest.raises(OptionError, match="no reachability map at"):
        ReachabilityMap.load(tmp_path / "missing.zarr")
    (tmp_path / "junk.npz").write_bytes(b"not a zip file")
    with pytest.raises(OptionError, match="no reachability map written by kinengine"):
        ReachabilityMap.load(tmp_path / "junk.npz")
    with pytest.raises(OptionError, match="must be a ReachabilityMap"):
        base_placements(str(tmp_path / "m.zarr"), np.eye(4))
    bad = np.eye(4)
    bad[0, 3] = np.nan
    with pytest.raises(OptionError, match="NaN"):
        abb_map.reachable(bad)


def test_cli_place_and_reach_name_what_is_wrong(tmp_path, capsys):
    from kinengine.cli.main import main

    np.save(tmp_path / "t.npy", np.eye(4)[None])
    assert main(["place", str(tmp_path / "nope.zarr"), "--targets", str(tmp_path / "t.npy")]) == 2
    assert "no reachability map at" in capsys.readouterr().err
    pytest.importorskip("distributed")
    out = str(tmp_path / "x.zarr")
    assert main(["reach", "planar_3dof", "--voxel", "0.5", "-o", out, "--scheduler", "bogus"]) == 2
    assert "cannot reach the Dask scheduler 'bogus'" in capsys.readouterr().err
