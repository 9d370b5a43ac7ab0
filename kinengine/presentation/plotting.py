"""A matplotlib 3D picture of a robot at q: skeleton, joint axes, frame triads, velocity ellipsoid.

Everything is drawn in the root link frame I (Pinocchio's "world"), lengths in m:
* the skeleton: one segment per URDF joint, from the parent link's origin to the child link's origin
  (a joint's frame is its child link's frame), fixed joints included, so it reaches the tool frames;
* each movable joint's axis as an arrow at the joint origin (mimic joints too);
* chosen frames as RGB triads (x red, y green, z blue) with their names;
* optionally the velocity manipulability ellipsoid {J_v q̇ : |q̇| <= 1} of one frame, centred at its
  origin and scaled by ``Drawing.ellipsoid_scale`` [m per m/s] to be visible (the legend says by how much).
The title gives the robot, q, and the pose of the first chosen frame (else the end effector): position
[m] and rotation vector φ = θ·n [rad]. The numbers behind the picture are in ``ax.kinengine_drawing``.
matplotlib is imported lazily, so that ``import kinengine`` and the other commands stay fast.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Real
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..control.manipulability import VelocityEllipsoid
from ..errors import KinematicsError

if TYPE_CHECKING:
    import matplotlib.axes
    from mpl_toolkits.mplot3d.axes3d import Axes3D  # no type information: Any to the checker

    from ..control.robot_like import RobotLike

PLOT_EXTRA = "pip install 'kinengine[plot]'"
"""What installs matplotlib for kinengine: the ``plot`` extra."""


def pyplot(*, headless: bool = False) -> ModuleType:
    """``matplotlib.pyplot``; with ``headless``, on the Agg backend (files, no window). matplotlib is an
    optional dependency: without it, a KinematicsError naming the ``plot`` extra."""
    try:
        import matplotlib
    except ImportError:
        raise KinematicsError(f"pictures need matplotlib, which is not installed: {PLOT_EXTRA}") from None
    if headless:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


AXIS_FRACTION = 0.15
"""Default arrow and triad length as a fraction of the skeleton's largest extent."""
ELLIPSOID_FRACTION = 0.3
"""The ellipsoid's longest drawn semi-axis, about this fraction of the skeleton's largest extent."""
TITLE_WIDTH = 92
"""Characters per title line (fits a 6 in wide figure at font size 8)."""
_TRIAD_COLORS = ("tab:red", "tab:green", "tab:blue")


@dataclass(frozen=True)
class Drawing:
    """The data a robot picture was built from, in the root link frame I [m].

    ``skeleton`` (M, 2, 3): parent link origin -> child link origin of URDF joint ``skeleton_joints[i]``;
    ``joint_axes``: movable joint -> (origin (3,), unit axis direction (3,));
    ``frames``: triad frame -> T_IF (4, 4); ``ellipsoid``: the velocity ellipsoid (or None), drawn with
    semi-axes ``ellipsoid_scale`` · semi_axes; ``axis_length``: length of arrows and triads [m].
    """

    q: np.ndarray
    skeleton: np.ndarray
    skeleton_joints: tuple[str, ...]
    joint_axes: dict[str, tuple[np.ndarray, np.ndarray]]
    frames: dict[str, np.ndarray]
    ellipsoid: VelocityEllipsoid | None
    ellipsoid_frame: str | None
    ellipsoid_scale: float
    axis_length: float
    title: str


def drawing(
    robot: RobotLike,
    q: npt.ArrayLike | None = None,
    *,
    frames: Sequence[str] = (),
    ellipsoid: str | None = None,
    axis_length: float | None = None,
) -> Drawing:
    """The :class:`Drawing` of ``robot`` at q (dof,) (None: neutral), without drawing anything."""
    q = robot.neutral() if q is None else robot.check_configuration(q, check_limits=False, batch=False)
    frames = (frames,) if isinstance(frames, str) else tuple(frames or ())
    triads = {name: robot.frame_pose(q, name) for name in frames}  # FrameNotFoundError names unknown frames
    joints = robot.description.joints
    link_pose = {robot.description.root: np.eye(4)}
    link_pose.update((j.child, robot.frame_pose(q, j.child)) for j in joints)
    skeleton = np.array([(link_pose[j.parent][:3, 3], link_pose[j.child][:3, 3]) for j in joints])
    skeleton = skeleton.reshape(-1, 2, 3)
    joint_axes = {
        j.name: (link_pose[j.child][:3, 3].copy(), link_pose[j.child][:3, :3] @ np.asarray(j.axis))
        for j in joints
        if j.movable
    }
    span = float(np.ptp(skeleton.reshape(-1, 3), axis=0).max()) if len(skeleton) else 0.0
    span = span if span > 0 else 1.0
    if axis_length is None:
        axis_length = AXIS_FRACTION * span
    elif not (isinstance(axis_length, Real) and np.isfinite(axis_length) and axis_length > 0):
        raise KinematicsError(f"axis_length must be a positive length in m, got {axis_length!r}")
    ellipse, scale = None, 0.0
    if ellipsoid is not None:
        ellipse = robot.velocity_ellipsoid(q, ellipsoid)
        longest = float(ellipse.semi_axes[0])
        scale = float(f"{ELLIPSOID_FRACTION * span / longest:.1g}") if longest > 0 else 1.0
    return Drawing(
        q,
        skeleton,
        tuple(j.name for j in joints),
        joint_axes,
        triads,
        ellipse,
        ellipsoid,
        scale,
        float(axis_length),
        _title(robot, q, frames[0] if frames else robot.end_effector),
    )


def plot_robot(
    robot: RobotLike,
    q: npt.ArrayLike | None = None,
    ax: matplotlib.axes.Axes | None = None,
    *,
    frames: Sequence[str] = (),
    ellipsoid: str | None = None,
    axis_length: float | None = None,
    title: bool | str = True,
) -> matplotlib.axes.Axes:
    """Draw ``robot`` at q (None: neutral) into a 3D axes (new figure if ``ax`` is None); returns the axes.

    ``frames``: names drawn as RGB triads; ``ellipsoid``: frame whose velocity ellipsoid is drawn;
    ``axis_length``: arrow and triad length [m] (default 0.15 of the robot's extent); ``title``:
    True for robot, q and pose, a string for your own, False for none. ``ax.kinengine_drawing`` holds
    the :class:`Drawing`. Never calls ``plt.show()``. Sets ``ax.computed_zorder = False`` (layers are
    drawn in a fixed order so that joint axes along a link stay visible).
    """
    plt = pyplot()
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    if ax is not None and getattr(ax, "name", None) != "3d":
        raise KinematicsError("`ax` must be a 3D axes, e.g. fig.add_subplot(projection='3d')")
    d = drawing(robot, q, frames=frames, ellipsoid=ellipsoid, axis_length=axis_length)
    ax3d: Axes3D = plt.figure(figsize=(6, 6)).add_subplot(projection="3d") if ax is None else ax
    ax3d.computed_zorder = False  # painter's order below: ellipsoid, links, joint axes, triads
    points = [np.zeros((1, 3)), d.skeleton.reshape(-1, 3)]

    if d.ellipsoid is not None:
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
        sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)])
        surface = d.ellipsoid.center[:, None, None] + np.einsum(
            "ij,jkl->ikl", d.ellipsoid.axes * (d.ellipsoid_scale * d.ellipsoid.semi_axes), sphere
        )
        ax3d.plot_wireframe(
            *surface,
            color="tab:cyan",
            linewidth=0.5,
            alpha=0.6,
            zorder=1,
            label=f"velocity ellipsoid of {d.ellipsoid_frame}, ×{d.ellipsoid_scale:g} "
            f"(1 m/s per unit $|\\dot{{q}}|$ drawn as {d.ellipsoid_scale:g} m)",
        )
        points.append(surface.reshape(3, -1).T)

    if len(d.skeleton):  # a robot of one link has no segment to draw
        ax3d.add_collection3d(
            Line3DCollection(
                d.skeleton,
                colors="0.25",
                linewidths=2.5,
                zorder=2,
                label="links (joint origin to joint origin)",
            )
        )
        ax3d.scatter(*d.skeleton.reshape(-1, 3).T, color="0.25", s=12, depthshade=False, zorder=2)
    ax3d.scatter(
        0,
        0,
        0,
        color="k",
        marker="s",
        s=30,
        depthshade=False,
        zorder=2,
        label=f"root {robot.description.root}",
    )

    types = {j.name: j.type for j in robot.description.joints}
    for kind, color in (("revolute", "tab:orange"), ("prismatic", "tab:purple")):
        names = [n for n in d.joint_axes if (types[n] == "prismatic") == (kind == "prismatic")]
        if names:
            origin, direction = (np.array([d.joint_axes[n][i] for n in names]) for i in (0, 1))
            ax3d.quiver(
                *origin.T,
                *direction.T,
                length=d.axis_length,
                color=color,
                linewidths=2,
                arrow_length_ratio=0.3,
                zorder=3,
                label=f"{kind} joint axes",
            )
            points.append(origin + d.axis_length * direction)

    for name, T in d.frames.items():
        for k in range(3):
            ax3d.quiver(
                *T[:3, 3],
                *T[:3, k],
                length=d.axis_length,
                color=_TRIAD_COLORS[k],
                linewidths=2,
                arrow_length_ratio=0.2,
                zorder=4,
            )
        ax3d.text(*(T[:3, 3] + 0.3 * d.axis_length * T[:3, :3].sum(axis=1)), name, fontsize=8, zorder=5)
        points.append(T[:3, 3] + d.axis_length * T[:3, :3].T)

    cloud = np.concatenate(points)
    centre = (cloud.max(axis=0) + cloud.min(axis=0)) / 2
    half = 0.55 * max(float(np.ptp(cloud, axis=0).max()), d.axis_length)
    ax3d.set(
        xlim=(centre[0] - half, centre[0] + half),
        ylim=(centre[1] - half, centre[1] + half),
        zlim=(centre[2] - half, centre[2] + half),
        xlabel="x [m]",
        ylabel="y [m]",
        zlabel="z [m]",
    )
    ax3d.set_box_aspect((1, 1, 1))
    ax3d.legend(loc="upper left", fontsize=7)
    if title:
        ax3d.set_title(d.title if title is True else str(title), fontsize=8)
    ax3d.kinengine_drawing = d
    return ax3d


def _title(robot: RobotLike, q: np.ndarray, frame: str) -> str:
    """'<robot> at q = (...) [rad]', then ``frame``'s pose in the root frame: p [m], rotation vector [rad]."""
    types = {j.type for j in robot.description.joints if j.movable and j.mimic is None}
    unit = "m" if types == {"prismatic"} else "rad, m" if "prismatic" in types else "rad"
    chi = robot.pose_parameters(q, frame, "cartesian", "rotation_vector", on_singularity=None)
    lines = (
        f"{robot.name} at q = {_vector(q, '.3g')} [{unit}]",
        f"{frame} in {robot.description.root}: p = {_vector(chi[:3])} m, "
        f"rotation vector {_vector(chi[3:])} rad",
    )
    return "\n".join(textwrap.fill(line, TITLE_WIDTH) for line in lines)


def _vector(values: np.ndarray, spec: str = ".3f") -> str:
    """'(0.1, -0.3)': values rounded to ``spec`` (no '-0')."""
    return "(" + ", ".join(format(float(v) + 0.0, spec) for v in np.round(values, 3)) + ")"


__all__ = ["Drawing", "drawing", "plot_robot"]
