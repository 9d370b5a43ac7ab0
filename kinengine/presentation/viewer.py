"""The browser viewer: a robot at q in 3D (Viser), with sliders, frame triads, ellipsoid and χ readout.

``view(robot, q)`` serves a page (default http://127.0.0.1:8080, the next free port if taken) showing
* the links' visuals (URDF boxes, cylinders, spheres and STL/DAE/OBJ meshes, see :mod:`.viewer_scene`)
  placed at T_IL from kinengine's forward kinematics, and the skeleton (parent -> child link origins);
* one slider per coordinate of q within its limits [rad or m] (continuous joints ±π);
* RGB triads (x red, y green, z blue) of the frames asked for;
* optionally the velocity manipulability ellipsoid {J_v q̇ : |q̇| <= 1} of one frame, drawn with its
  semi-axes [m/s per unit |q̇|] scaled by ``Viewer.ellipsoid_scale`` [m per m/s] to be visible;
* a readout of χ_e = (χ_P cartesian [m], χ_R [rad]) of the readout frame (the ellipsoid's frame, else
  the end effector) for a chosen rotation parameterization, and the distance of χ_R to the singular
  set of that parameterization (where the analytic Jacobian E_R · J_e0 does not exist; Robot Dynamics
  lecture notes, ETH Zurich, section 2.8), shown in red below ``singularity_warning``.
Everything is in the root link frame I, z up. ``Viewer.update(q)`` moves the robot in every open
page (a control loop can be watched live). Viser is an optional extra: ``pip install 'kinengine[view]'``.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import threading
import warnings
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import KinematicsError
from ..parameterizations import ROTATION_PARAMETERIZATIONS, get_rotation
from . import viewer_host as host_
from . import viewer_nodes as nodes
from . import viewer_scene as scene

if TYPE_CHECKING:
    from ..control.robot_like import RobotLike

DEFAULT_PORT = 8080
SINGULARITY_WARNING = 0.1
"""Distance of χ_R to its singular set below which the readout turns red (|sin|, |cos| or radius scale)."""
FOV = math.radians(50.0)
"""Vertical field of view of the initial camera [rad]."""
_TRIAD = ((230, 40, 40), (40, 170, 40), (40, 80, 230))


def _viser() -> Any:
    try:
        import trimesh  # noqa: F401  (read meshes; a dependency of yourdfpy, checked here all the same)
        import viser
    except ImportError as exc:
        raise KinematicsError(
            f"the viewer needs the optional packages viser and trimesh ({exc.name} is "
            "missing): pip install 'kinengine[view]'"
        ) from None
    return viser


class Viewer:
    """A running viewer of one robot; build it with :func:`view` or ``robot.view(q)``.

    ``Viewer(robot, q)`` (alias ``view``) serves ``robot`` at q (dof,) (None: neutral) in the browser.
    ``port`` None: 8080 (the next free one if taken; 0: any free port; ``Viewer.url`` says which);
    ``frames``: frames drawn as triads; ``ellipsoid``: frame whose velocity ellipsoid is drawn (and whose
    pose the readout shows; default: the end effector); ``parameterization``: the rotation
    parameterization of the readout; ``meshes=False`` draws URDF primitives and the skeleton only;
    ``packages`` maps ROS package names to folders for ``package://`` mesh files (default: the robot's
    ``packages``, then ``ROS_PACKAGE_PATH``, then the folders above the robot's file); ``host``
    "0.0.0.0" serves the network (with a one-line warning; None or "" is refused, a name that does not
    resolve within a few seconds or an address of another machine too: OptionError).

    ``url``: the page; ``address``: the numeric address listened on; ``port``: the port; ``q``: the
    configuration shown (dof,) [rad or m]; ``update(q)`` moves the robot; ``close()`` stops the server
    (also on leaving a ``with`` block). ``camera_position`` and ``camera_look_at`` [m, in I] and ``fov``
    [rad] describe the initial camera of a new page.
    """

    def __init__(
        self,
        robot: RobotLike,
        q: npt.ArrayLike | None = None,
        *,
        port: int | None = None,
        host: str = "127.0.0.1",
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        parameterization: str = "euler_zyx",
        meshes: bool = True,
        singularity_warning: float = SINGULARITY_WARNING,
        packages: Mapping[str, str | os.PathLike] | None = None,
    ) -> None:
        viser = _viser()
        self.robot = robot
        q0: np.ndarray = robot.neutral() if q is None else robot.check_configuration(q, batch=False)
        for name in (*frames, *([ellipsoid] if ellipsoid is not None else [])):
            robot.frame_id(name)  # FrameNotFoundError with suggestions
        get_rotation(parameterization)  # ParameterizationError naming the choices
        port = host_.checked_port(port)
        self.address = host_.listen_address(host)  # bounded wait; warns when not loopback
        self.frames, self.ellipsoid_frame = tuple(frames), ellipsoid
        self.readout_frame = ellipsoid if ellipsoid is not None else robot.end_effector
        self.singularity_warning = float(singularity_warning)
        self._lock = threading.RLock()
        self._collisions: Any = None  # the collision layer, built by show_collisions()
        self._links = tuple(link.name for link in robot.description.links)
        visuals = scene.read_visuals(
            robot.urdf_text,
            robot.source,
            meshes=meshes,
            packages=robot.packages if packages is None else packages,
        )
        if visuals.error is not None:
            warnings.warn(
                f"the visuals of {robot.name} could not be read ({visuals.error}); the robot is "
                "drawn as its skeleton",
                UserWarning,
                stacklevel=2,  # the caller of Viewer(...) / view(...)
            )
        elif visuals.failures:
            (first, why), n = visuals.failures[0], len(visuals.failures)
            warnings.warn(
                f"{n} mesh{'es' if n > 1 else ''} of {robot.name} could not be used "
                f"(first: {first}: {why}); "
                f"{'those links are' if n > 1 else 'that link is'} drawn as skeleton only",
                UserWarning,
                stacklevel=2,
            )

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints a banner; the URL is self.url
            self._server = server = viser.ViserServer(
                host=self.address,
                port=DEFAULT_PORT if port is None else port,
                label=f"kinengine: {robot.name}",
                verbose=False,
            )
        try:
            self._build(server, visuals, q0, parameterization)
        except BaseException:
            self.close()
            raise
        self.port: int = server.get_port()
        self.url = host_.url(self.address, self.port)

    # -- scene -------------------------------------------------------------------------------
    def _build(self, server: Any, visuals: scene.Visuals, q: np.ndarray, parameterization: str) -> None:
        server.scene.set_up_direction("+z")
        server.scene.add_grid("/grid", width=2.0, height=2.0, cell_size=0.1, plane="xy")
        poses = scene.link_poses(self.robot, q, self._links)
        points = np.array([T[:3, 3] for T in poses.values()])
        extent = float(np.ptp(points, axis=0).max()) if len(points) > 1 else 0.5
        self.axis_length = max(0.15 * extent, 0.02)
        self.ellipsoid_scale = 1.0
        self.camera_position, self.camera_look_at = scene.camera(points, FOV)
        self.fov = FOV
        server.initial_camera.position = tuple(self.camera_position)
        server.initial_camera.look_at = tuple(self.camera_look_at)
        server.initial_camera.fov = FOV

        self._root = server.scene.add_frame("/robot", show_axes=False)
        self._link_nodes = {}
        for i, link in enumerate(self._links):
            node = server.scene.add_frame(f"/robot/{i}_{scene.node_name(link)}", show_axes=False)
            self._link_nodes[link] = node
            for k, v in enumerate(visuals.links.get(link, ())):
                nodes.add_visual(server, f"{node.name}/visual_{k}", v)
        self._skeleton = server.scene.add_line_segments(
            "/robot/skeleton",
            scene.skeleton(self.robot, poses),
            colors=(60, 60, 60),
            thickness=max(0.004, 0.01 * extent),
        )
        length = self.axis_length
        self._triads = {
            name: server.scene.add_frame(
                f"/frames/{scene.node_name(name)}", axes_length=length, axes_radius=length / 25
            )
            for name in self.frames
        }
        self._ellipsoid = None
        if self.ellipsoid_frame is not None:
            semi = self.robot.velocity_ellipsoid(q, self.ellipsoid_frame).semi_axes
            self.ellipsoid_scale = 0.3 * extent / max(float(semi.max()), 1e-9)
            sphere = scene.unit_sphere()
            self._sphere = sphere
            self._ellipsoid = server.scene.add_mesh_simple(
                "/ellipsoid", sphere[0], sphere[1], color=(230, 150, 30), opacity=0.45, side="double"
            )
        self._build_gui(server, parameterization)
        self.q = q
        self._apply(q, from_gui=False)

    def _build_gui(self, server: Any, parameterization: str) -> None:
        ranges = scene.slider_ranges(self.robot)
        self._sliders = []
        with server.gui.add_folder("Coordinates q [rad | m]"):
            for name, (lo, hi) in zip(self.robot.joint_names, ranges, strict=True):
                slider = server.gui.add_slider(
                    name, min=lo, max=hi, step=1e-3, initial_value=min(max(0.0, lo), hi)
                )
                slider.on_update(self._on_slider)
                self._sliders.append(slider)
        with server.gui.add_folder(f"Pose of {self.readout_frame}"):
            self._parameterization = server.gui.add_dropdown(
                "rotation", tuple(ROTATION_PARAMETERIZATIONS), initial_value=parameterization
            )
            self._parameterization.on_update(lambda _: self._refresh_readout())
            self._readout = server.gui.add_html("")
        self._robot_visible = server.gui.add_checkbox("show robot", True)
        self._robot_visible.on_update(lambda _: self.show_robot(self._robot_visible.value))

    # -- updates -----------------------------------------------------------------------------
    def update(self, q: npt.ArrayLike) -> None:
        """Show configuration q (dof,) [rad or m] in every open page (checked like every kinengine input)."""
        q_checked: np.ndarray = self.robot.check_configuration(q, batch=False, check_limits=False)
        if self._server is None:
            raise KinematicsError("this viewer is closed; open a new one with robot.view(q)")
        with self._lock:
            self._apply(q_checked, from_gui=False)

    def _on_slider(self, event: Any) -> None:
        if event.client is None:  # set by update(), not by a user
            return
        with self._lock:
            q = self.q.copy()
            q[self._sliders.index(event.target)] = float(event.target.value)
            self._apply(q, from_gui=True)

    def _apply(self, q: np.ndarray, *, from_gui: bool) -> None:
        self.q = q
        poses = scene.link_poses(self.robot, q, self._links)
        with self._server.atomic():
            for link, node in self._link_nodes.items():
                node.position, node.wxyz = poses[link][:3, 3], scene.wxyz(poses[link][:3, :3])
            self._skeleton.points = scene.skeleton(self.robot, poses)
            for name, node in self._triads.items():
                T = self.robot.frame_pose(q, name)
                node.position, node.wxyz = T[:3, 3], scene.wxyz(T[:3, :3])
            if self._ellipsoid is not None:
                e = self.robot.velocity_ellipsoid(q, self.ellipsoid_frame)
                shape = e.axes @ np.diag(self.ellipsoid_scale * np.maximum(e.semi_axes, 1e-4))
                self._ellipsoid.vertices = (self._sphere[0] @ shape.T + e.center).astype(np.float32)
            if not from_gui:
                for slider, value in zip(self._sliders, q, strict=True):
                    slider.value = min(max(float(value), slider.min), slider.max)
            self._refresh_readout()
            if self._collisions is not None:
                self._collisions.update(q)

    def _refresh_readout(self) -> None:
        name = self._parameterization.value
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # gimbal lock: the readout says so in red
            chi = self.robot.pose_parameters(
                self.q, self.readout_frame, "cartesian", name, on_singularity=None
            )
        distance = float(get_rotation(name).singularity_distance(chi[3:]))
        self.readout = {"chi": chi, "distance": distance, "singular": distance < self.singularity_warning}
        labels = ("x", "y", "z", *get_rotation(name).labels)
        self._readout.content = nodes.readout_html(labels, chi, name, distance, self.singularity_warning)

    def shown_pose(self, link: str) -> npt.NDArray[np.float64]:
        """T_IL (4, 4) [m] of ``link`` as sent to the browser (position and quaternion of its scene node)."""
        return nodes.node_pose(self._link_nodes[link])

    def show_collisions(self, visible: bool = True) -> list[tuple[str, str]]:
        """Show (or hide) the collision shapes and obstacles at the shown q, the shapes of colliding pairs in
        red; they follow :meth:`update`. Returns the colliding link pairs (see
        :mod:`.viewer_collisions`)."""
        from .viewer_collisions import CollisionLayer

        with self._lock:
            if not visible:
                if self._collisions is not None:
                    self._collisions.remove()
                self._collisions = None
                return []
            if self._collisions is None:
                self._collisions = CollisionLayer(self._server, self.robot.collision_checker())
            self._collisions.update(self.q)
            return list(self._collisions.colliding)

    def show_robot(self, visible: bool = True) -> None:
        """Show or hide the robot (visuals and skeleton); frames and the ellipsoid stay."""
        self._root.visible = bool(visible)
        self._robot_visible.value = bool(visible)  # the page's checkbox follows (no-op if it is the caller)

    def add_points(self, name: str, points: npt.ArrayLike, colors: npt.ArrayLike, size: float) -> None:
        """Show points (n, 3) [m, root link frame] with RGB ``colors`` (n, 3) uint8 as squares of ``size`` [m]
        under the scene node ``name`` (e.g. a reachability map's voxels); the same name replaces them."""
        P = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 3)
        C = np.ascontiguousarray(colors, dtype=np.uint8).reshape(-1, 3)
        if len(C) != len(P):
            raise KinematicsError(f"{len(P)} points but {len(C)} colors")
        with self._lock:
            server = self._server
            if server is None:
                raise KinematicsError("the viewer is closed")
            server.scene.add_point_cloud(
                name, points=P, colors=C, point_size=float(size), point_shape="square"
            )

    # -- lifetime ----------------------------------------------------------------------------
    def close(self) -> None:
        """Stop the server (pages lose their connection); safe to call twice."""
        server, self._server = getattr(self, "_server", None), None
        if server is not None:
            with contextlib.redirect_stdout(io.StringIO()):  # "(viser) Server stopped"
                server.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<kinengine Viewer of {self.robot.name} at {self.url}>"


view = Viewer
"""``view(robot, q, ...)``: serve ``robot`` in the browser and return the running :class:`Viewer` (the
Viewer's constructor, under the name the docs and ``robot.view(q)`` use)."""


__all__ = ["DEFAULT_PORT", "FOV", "SINGULARITY_WARNING", "Viewer", "view"]
