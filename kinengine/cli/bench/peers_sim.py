"""The MuJoCo and Drake adapters of ``kinengine bench --peers`` (:class:`SimulatorPeers`, mixed into
:class:`kinengine.cli.bench.peers.Peer`; see that module for what each peer calls), and what every adapter
shares: :class:`Skip` and the loop limit LOOP_MAX. Both simulators read kinengine's canonical URDF; their
answers are converted back to T_IF (4, 4) [m] and J (6, dof) rows [v; ω] in kinengine's joint order.
"""

from __future__ import annotations

from typing import Any

import numpy as np

LWA_CASE = "jacobian[local_world_aligned]"
LOOP_MAX = 10_000
"""Batches larger than this are not timed for peers that need a Python loop over configurations."""


class Skip(Exception):
    """A case this peer is not timed on (the message says why)."""


class SimulatorPeers:
    """Loading (``_load_<name>``) and per-case preparation (``_prepare_<name>``) for mujoco and drake."""

    robot: Any  # the kinengine Robot the peer is loaded for
    frame: str
    name: str

    @staticmethod
    def _loop(case) -> None:
        if case.n > LOOP_MAX:
            raise Skip(f"Python loop over configurations: not timed above N = {LOOP_MAX:,}")

    # -- mujoco -------------------------------------------------------------------------------------
    def _load_mujoco(self) -> None:
        import mujoco

        xml = self.robot.description.to_xml()
        head = xml.index(">", xml.index("<robot")) + 1
        compiler = (
            '<mujoco><compiler discardvisual="true" fusestatic="false" boundmass="1e-6" '
            'boundinertia="1e-9" autolimits="true"/></mujoco>'
        )
        spec = mujoco.MjSpec.from_string(xml[:head] + compiler + xml[head:])
        spec.body(self.frame).add_site(name="kinengine_frame", pos=[0.0, 0.0, 0.0])
        self._mj = mujoco
        self._mj_model = spec.compile()
        self._mj_data = mujoco.MjData(self._mj_model)
        self._mj_site = mujoco.mj_name2id(self._mj_model, mujoco.mjtObj.mjOBJ_SITE, "kinengine_frame")
        names = [
            mujoco.mj_id2name(self._mj_model, mujoco.mjtObj.mjOBJ_JOINT, j)
            for j in range(self._mj_model.njnt)
        ]
        self._mj_order = self._pinocchio_order(names)

    def _pinocchio_order(self, names: list[str]) -> np.ndarray:
        """Index into Pinocchio's configuration q_pin (every movable joint, mimic ones too) per peer joint."""
        pin_names = list(self.robot.engine.coordinates.pinocchio_names)
        return np.array([pin_names.index(n) for n in names], dtype=np.intp)

    def _pinocchio_q(self, case) -> np.ndarray:
        Q = np.atleast_2d(case.q)
        return np.array([self.robot.pinocchio_configuration(q) for q in Q])

    def _fold(self, J_peer: np.ndarray, order: np.ndarray) -> np.ndarray:
        """A Jacobian (..., 6, peer dofs) as kinengine's (..., 6, dof): Pinocchio's columns, then
        J_pin · M."""
        J_pin = np.zeros(J_peer.shape[:-1] + (len(self.robot.engine.coordinates.pinocchio_names),))
        J_pin[..., order] = J_peer
        return self.robot.engine.coordinates.fold(J_pin)

    def _prepare_mujoco(self, case, single: bool):
        if case.name not in ("frame_pose", LWA_CASE):
            return None
        mujoco, model, data, site = self._mj, self._mj_model, self._mj_data, self._mj_site
        kinematics, com_pos, jac_site = mujoco.mj_kinematics, mujoco.mj_comPos, mujoco.mj_jacSite
        X = self._pinocchio_q(case)[:, self._mj_order]
        if not single:
            self._loop(case)
        qpos, xpos, xmat = data.qpos, data.site_xpos, data.site_xmat
        if case.name == "frame_pose":

            def pose(x):
                qpos[:] = x
                kinematics(model, data)
                T = np.eye(4)
                T[:3, :3] = xmat[site].reshape(3, 3)
                T[:3, 3] = xpos[site]
                return T

            if single:
                x = X[0]
                return (lambda: pose(x)), np.asarray
            return (lambda: [pose(x) for x in X]), np.asarray
        nv = model.nv

        def jacobian(x):
            qpos[:] = x
            kinematics(model, data)
            com_pos(model, data)
            J = np.empty((6, nv))
            jac_site(model, data, J[:3], J[3:], site)
            return J

        def convert(out):
            return self._fold(np.asarray(out), self._mj_order)

        if single:
            x = X[0]
            return (lambda: jacobian(x)), convert
        return (lambda: [jacobian(x) for x in X]), convert

    # -- drake ----------------------------------------------------------------------------------------
    def _load_drake(self) -> None:
        from pydrake.multibody.parsing import Parser
        from pydrake.multibody.plant import MultibodyPlant
        from pydrake.multibody.tree import JacobianWrtVariable

        plant = MultibodyPlant(0.0)
        Parser(plant).AddModelsFromString(self.robot.description.to_xml(), "urdf")
        root = self.robot.description.root
        if root != "world":  # Drake's URDF "world" link is the world body already
            plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(root))
        plant.Finalize()
        self._drake = plant
        self._drake_context = plant.CreateDefaultContext()
        self._drake_frame = plant.GetFrameByName(self.frame)
        self._drake_qdot = JacobianWrtVariable.kQDot
        pin_names = self.robot.engine.coordinates.pinocchio_names
        self._drake_index = np.array(
            [plant.GetJointByName(n).position_start() for n in pin_names], dtype=np.intp
        )

    def _prepare_drake(self, case, single: bool):
        if case.name not in ("frame_pose", LWA_CASE):
            return None
        plant, context, frame, world = (
            self._drake,
            self._drake_context,
            self._drake_frame,
            self._drake.world_frame(),
        )
        QP = self._pinocchio_q(case)
        X = np.zeros((len(QP), plant.num_positions()))
        X[:, self._drake_index] = QP
        if not single:
            self._loop(case)
        set_positions, origin = plant.SetPositions, np.zeros(3)
        if case.name == "frame_pose":
            transform = plant.CalcRelativeTransform

            def pose(x):
                set_positions(context, x)
                return transform(context, world, frame).GetAsMatrix4()

            fn = (lambda: pose(X[0])) if single else (lambda: [pose(x) for x in X])
            return fn, np.asarray
        spatial, qdot = plant.CalcJacobianSpatialVelocity, self._drake_qdot

        def jacobian(x):
            set_positions(context, x)
            return spatial(context, qdot, frame, origin, world, world)

        def convert(out):
            J = np.asarray(out)[..., [3, 4, 5, 0, 1, 2], :][
                ..., self._drake_index
            ]  # [v; ω], Pinocchio's columns
            return self.robot.engine.coordinates.fold(J)

        fn = (lambda: jacobian(X[0])) if single else (lambda: [jacobian(x) for x in X])
        return fn, convert


__all__ = ["LOOP_MAX", "LWA_CASE", "SimulatorPeers", "Skip"]
