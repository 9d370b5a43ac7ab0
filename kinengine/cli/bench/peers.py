"""Other kinematics libraries timed by ``kinengine bench --peers`` on the same URDF, where installed.

* ``roboticstoolbox`` (roboticstoolbox-python): ``Robot.URDF(file)``, then the compiled ETS of the
  path to the frame: ``ets.fkine(q)``, ``ets.jacob0(q)`` (origin velocity and ω in the base frame,
  i.e. "local_world_aligned"); ``ets.fkine(Q)`` for a batch, ``jacob0`` in a loop;
  ``ets.jacob0_analytical(q, representation)`` for the analytic Jacobians it has: "eul" is
  euler_zyz, "exp" rotation_vector, "rpy/zyx" and "rpy/xyz" are euler_zyx and euler_xyz with the
  three angle rows in reverse order (roll first).
* ``pytorch_kinematics`` (CPU torch, float64): ``build_serial_chain_from_urdf(text, frame)``;
  ``forward_kinematics(th).get_matrix()`` and ``jacobian(th)`` (base frame), natively batched.
  (0.10.0 parses every ``<origin rpy>`` as float32, whatever the chain's dtype: on the ABB IRB 120
  its poses differ from kinengine's by 6e-9 m, so at the default ``--peer-atol`` it is reported, not timed.)
* ``ikpy``: ``Chain.from_urdf_file`` along the path to the frame; ``forward_kinematics`` only
  (no Jacobian), one configuration per call.
* ``mujoco``: kinengine's canonical URDF (no meshes) with a ``<mujoco><compiler fusestatic="false" .../>``
  tag, a site added at the frame (``MjSpec``); per call ``mj_kinematics`` + ``mj_comPos``, then the
  site pose (``site_xpos``/``site_xmat``) or ``mj_jacSite`` (origin velocity and ω in the world: rows
  [jacp; jacr] = "local_world_aligned"). One configuration per call (batches loop in Python).
* ``drake`` (pydrake): ``MultibodyPlant`` from the canonical URDF, root welded to the world;
  ``SetPositions`` then ``CalcRelativeTransform`` or ``CalcJacobianSpatialVelocity`` (rows [ω; v],
  reordered to [v; ω]).
* IK rows: roboticstoolbox's C++ ``ets.ik_LM`` per target (joint limits on) at ``RTB_IK_TOL`` = 5e-13 on
  ½eᵀe, i.e. |e| <= 1e-6 over position [m] and rotation [rad] rows together: the accuracy kinengine is
  asked for (its default tolerance, 1e-12, stops at |e| <= 1.4e-6 and leaves ~2 % of the targets outside
  1e-6). Both are counted as reached by the same rule (1e-6 m, 1e-6 rad, within limits), and the rows show
  each library's achieved error next to its rate.

Each adapter maps kinengine's q (``joint_names`` order) to the peer's joint order once, outside the
timed call, and converts the peer's answer back for the agreement check. Peers read the robot's own
file (``robot.source``) or text; one that cannot resolve its ``package://`` references gets
kinengine's canonical XML of the same description instead (said in its status).
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import io
import tempfile
import warnings

import numpy as np

from .peers_sim import LOOP_MAX, LWA_CASE, SimulatorPeers, Skip

PEERS = ("roboticstoolbox", "pytorch_kinematics", "ikpy", "mujoco", "drake")
_DISTRIBUTIONS = {
    "roboticstoolbox": "roboticstoolbox-python",
    "pytorch_kinematics": "pytorch-kinematics",
    "ikpy": "ikpy",
    "mujoco": "mujoco",
    "drake": "drake",
}
RTB_IK_TOL = 5e-13
"""ik_LM's tolerance on ½eᵀe: |e| <= 1e-6, kinengine's default tolerances (1e-6 m, 1e-6 rad)."""
RUNTIMES = {"pytorch_kinematics": ("torch",), "roboticstoolbox": ("spatialmath-python",)}
"""Libraries a peer runs on, whose versions the JSON records too."""
_ANALYTIC = "analytic_jacobian["
_REVERSED = [0, 1, 2, 5, 4, 3]
RTB_ANALYTIC = {
    "euler_zyz": ("eul", slice(None)),
    "rotation_vector": ("exp", slice(None)),
    "euler_zyx": ("rpy/zyx", _REVERSED),
    "euler_xyz": ("rpy/xyz", _REVERSED),
}
"""kinengine rotation -> (roboticstoolbox representation, its rows in kinengine's order)."""


class Peer(SimulatorPeers):
    """One library loaded for one robot and frame; ``prepare(case)`` gives (timed call, to-numpy)."""

    def __init__(self, name: str, robot, frame: str) -> None:
        self.name, self.distribution = name, _DISTRIBUTIONS[name]
        self.robot, self.frame = robot, frame
        self.loaded, self.note = False, ""
        self.version: str | None
        try:
            self.version = importlib.metadata.version(self.distribution)
        except importlib.metadata.PackageNotFoundError:
            self.version, self.note = None, f"not installed (pip install {self.distribution})"
            return
        try:
            with (
                contextlib.redirect_stdout(io.StringIO()),
                contextlib.redirect_stderr(io.StringIO()),
                warnings.catch_warnings(),
            ):  # e.g. ikpy on fixed links in its chain: its business
                warnings.simplefilter("ignore")
                self._load()
            self.loaded = True
        except Exception as exc:  # the peer cannot read this robot: a result, reported
            self.note = f"could not load: {type(exc).__name__}: {exc}"[:300]

    def status(self) -> dict:
        return {"version": self.version, "loaded": self.loaded, "note": self.note}

    def _path(self) -> str:
        """A file holding the robot's URDF kinematics for peers that only read files."""
        source = str(self.robot.source)
        if source.endswith(".urdf") and "package://" not in self.robot.urdf_text:
            return source
        self.note = "read kinengine's canonical XML (the original refers to package:// files)"
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as handle:
            handle.write(self.robot.description.to_xml())
        return handle.name

    def _order(self, names: list[str]) -> np.ndarray:
        """Index into kinengine's q for each peer joint (-1: not a kinengine coordinate, held at 0)."""
        index = {n: i for i, n in enumerate(self.robot.joint_names)}
        return np.array([index.get(n, -1) for n in names], dtype=np.intp)

    def _native(self, q: np.ndarray, order: np.ndarray) -> np.ndarray:
        q = np.atleast_2d(q)
        out = np.zeros(q.shape[:-1] + (len(order),))
        out[..., order >= 0] = q[..., order[order >= 0]]
        return out

    def prepare(self, case):
        """(timed call, result -> numpy in kinengine's convention), None if unsupported; may raise Skip."""
        if not self.loaded or (case.q is None and case.targets is None):
            return None
        if case.targets is not None and self.name != "roboticstoolbox":
            return None
        return getattr(self, f"_prepare_{self.name}")(case, case.q is not None and case.q.ndim == 1)

    # -- roboticstoolbox ------------------------------------------------------------------------------
    def _load_roboticstoolbox(self) -> None:
        import roboticstoolbox as rtb

        self._rtb = rtb.Robot.URDF(self._path())
        self._ets = self._rtb.ets(end=self.frame)
        by_index = {link.jindex: link.name for link in self._rtb.links if link.isjoint}
        child_to_joint = {j.child: j.name for j in self.robot.description.joints}
        self._rtb_order = self._order([child_to_joint.get(by_index[et.jindex]) for et in self._ets.joints()])

    def _prepare_roboticstoolbox(self, case, single: bool):
        ets = self._ets
        if case.targets is not None:
            targets = list(case.targets)

            def solve():
                return [ets.ik_LM(T, tol=RTB_IK_TOL, joint_limits=True)[0] for T in targets]

            return solve, (lambda out: np.array(out) @ self._unmap())
        x = self._native(case.q, self._rtb_order)
        if case.name == "frame_pose":
            if single:
                return (lambda: ets.fkine(x[0])), (lambda out: out.A)
            return (lambda: ets.fkine(x)), (lambda out: np.reshape(out.A, (-1, 4, 4)))  # N = 1: .A is (4, 4)
        if case.name == LWA_CASE:
            if single:
                return (lambda: ets.jacob0(x[0])), (lambda out: out @ self._unmap())
            self._loop(case)
            return (lambda: [ets.jacob0(xi) for xi in x]), (lambda out: np.array(out) @ self._unmap())
        if case.name.startswith(_ANALYTIC) and case.name[len(_ANALYTIC) : -1] in RTB_ANALYTIC:
            representation, rows = RTB_ANALYTIC[case.name[len(_ANALYTIC) : -1]]

            def to_kinengine(out):
                return np.asarray(out)[..., rows, :] @ self._unmap()

            if single:
                return (lambda: ets.jacob0_analytical(x[0], representation=representation)), to_kinengine
            self._loop(case)
            return (
                (lambda: [ets.jacob0_analytical(xi, representation=representation) for xi in x]),
                to_kinengine,
            )
        return None

    def _unmap(self) -> np.ndarray:
        """(peer columns, kinengine columns) selection matrix for the Jacobian's columns."""
        order = getattr(self, f"_{'rtb' if self.name == 'roboticstoolbox' else 'pk'}_order")
        P = np.zeros((len(order), self.robot.dof))
        P[np.flatnonzero(order >= 0), order[order >= 0]] = 1.0
        return P

    # -- pytorch_kinematics ---------------------------------------------------------------------------
    def _load_pytorch_kinematics(self) -> None:
        import pytorch_kinematics as pk
        import torch

        self._torch = torch
        chain = pk.build_serial_chain_from_urdf(self.robot.urdf_text.encode(), self.frame)
        self._chain = chain.to(dtype=torch.float64)
        self._pk_order = self._order(list(self._chain.get_joint_parameter_names()))

    def _prepare_pytorch_kinematics(self, case, single: bool):
        th = self._torch.tensor(self._native(case.q, self._pk_order))
        chain, pick = self._chain, (lambda a: a[0]) if single else (lambda a: a)
        if case.name == "frame_pose":
            return (lambda: chain.forward_kinematics(th).get_matrix()), (lambda out: pick(out.numpy()))
        if case.name == LWA_CASE:
            return (lambda: chain.jacobian(th)), (lambda out: pick(out.numpy()) @ self._unmap())
        return None

    # -- ikpy -----------------------------------------------------------------------------------------
    def _load_ikpy(self) -> None:
        from ikpy.chain import Chain

        description = self.robot.description
        parent_joint = {j.child: j for j in description.joints}
        path: list[str] = []
        link = self.frame
        while link in parent_joint:
            path[:0] = [parent_joint[link].name, parent_joint[link].child]
            link = parent_joint[link].parent
        if not path:
            raise ValueError(f"{self.frame!r} is not a link below the root")
        self._ikpy = Chain.from_urdf_file(self._path(), base_elements=[description.root] + path)
        names = [link.name for link in self._ikpy.links]
        self._ikpy_frame = names.index(path[-2])
        self._ikpy_order = self._order(names)

    def _prepare_ikpy(self, case, single: bool):
        if case.name != "frame_pose":
            return None
        x = self._native(case.q, self._ikpy_order)
        chain, k = self._ikpy, self._ikpy_frame
        if single:
            return (lambda: chain.forward_kinematics(x[0], full_kinematics=True)[k]), np.asarray
        self._loop(case)
        return (lambda: [chain.forward_kinematics(xi, full_kinematics=True)[k] for xi in x]), np.asarray

    def _load(self) -> None:
        getattr(self, f"_load_{self.name}")()


def load_peers(robot, frame: str) -> list[Peer]:
    """Every peer of PEERS loaded for ``robot``; ones missing or failing say why in their status."""
    return [Peer(name, robot, frame) for name in PEERS]


__all__ = ["LOOP_MAX", "PEERS", "RTB_ANALYTIC", "RUNTIMES", "Peer", "Skip", "load_peers"]
