"""Robot names that :func:`kinengine.load` accepts, and where their URDF files live.

Two sources: the descriptions shipped with kinengine (``robots/<name>/<name>.urdf``,
installed inside the wheel as ``kinengine/robots``) and the fixed-base arms of the
``example-robot-data`` distribution, located through its installed files (the PyPI
package ships URDFs but no Python loader). Meshes are never needed: only kinematics
is read.

Some entries are another entry with joints locked (``panda_arm``: the Panda with its finger
held at 0, 7 coordinates): :func:`kinengine.load` applies :meth:`Robot.locked` with
``CatalogEntry.locked``. ``CatalogEntry.extra_coordinates`` names the coordinates of a robot
that are not arm joints (gripper fingers), which a user usually wants to lock.

example-robot-data is looked up (with ``importlib.metadata``, slow to import) only for a name it may
provide or for the whole list: loading a shipped robot does not pay for it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ..errors import URDFError

_ERD_PREFIX = "cmeel.prefix/share/example-robot-data/robots"


@dataclass(frozen=True)
class CatalogEntry:
    """A loadable robot: its short name, URDF path, default end-effector frame and origin; the joints
    held fixed when it is loaded (joint name, value [rad or m]) and its gripper coordinates."""

    name: str
    path: Path
    end_effector: str | None
    origin: str  # "kinengine" or "example-robot-data"
    locked: tuple[tuple[str, float], ...] = ()
    extra_coordinates: tuple[str, ...] = ()


# Short name -> (path below the example-robot-data robots folder, default end-effector frame).
# Only fixed-base systems: legged, humanoid and flying robots need a floating base.
_ERD_ROBOTS: dict[str, tuple[str, str | None]] = {
    "ur3": ("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur3_limited": ("ur_description/urdf/ur3_joint_limited_robot.urdf", "tool0"),
    "ur3_gripper": ("ur_description/urdf/ur3_gripper.urdf", "tool0"),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur5_limited": ("ur_description/urdf/ur5_joint_limited_robot.urdf", "tool0"),
    "ur5_gripper": ("ur_description/urdf/ur5_gripper.urdf", "tool0"),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "ur10_limited": ("ur_description/urdf/ur10_joint_limited_robot.urdf", "tool0"),
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand"),
    "panda_arm": ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "kinova": ("kinova_description/robots/kinova.urdf", None),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", None),
    "z1": ("z1_description/urdf/z1.urdf", None),
    "so100": ("so_arm_description/urdf/so100.urdf", None),
    "so101": ("so_arm_description/urdf/so101.urdf", None),
    "baxter": ("baxter_description/urdf/baxter.urdf", None),
    "talos_left_arm": ("talos_data/robots/talos_left_arm.urdf", None),
    "double_pendulum": ("double_pendulum_description/urdf/double_pendulum.urdf", None),
    "double_pendulum_continuous": ("double_pendulum_description/urdf/double_pendulum_continuous.urdf", None),
    "double_pendulum_simple": ("double_pendulum_description/urdf/double_pendulum_simple.urdf", None),
    "asr_twodof": ("asr_twodof_description/urdf/TwoDofs.urdf", None),
    "finger_edu": ("finger_edu_description/robots/finger_edu.urdf", None),
    "allegro_left_hand": ("allegro_hand_description/urdf/allegro_left_hand.urdf", None),
    "allegro_right_hand": ("allegro_hand_description/urdf/allegro_right_hand.urdf", None),
}

_SHIPPED_END_EFFECTORS = {"abb_irb120": "tool0"}

# Short name -> joints locked on load (joint name, value).
_LOCKED: dict[str, tuple[tuple[str, float], ...]] = {"panda_arm": (("panda_finger_joint1", 0.0),)}

# Short name -> coordinates that move a gripper, not the arm (lock them with Robot.locked).
_EXTRA_COORDINATES: dict[str, tuple[str, ...]] = {
    "panda": ("panda_finger_joint1",),
    "baxter": ("l_gripper_l_finger_joint", "r_gripper_l_finger_joint"),
    "so100": ("gripper",),
    "so101": ("gripper",),
    "talos_left_arm": ("gripper_left_joint",),
    "z1": ("jointGripper",),
}

# End effectors that older releases of a file may lack: (wanted, used instead).
_FALLBACK_END_EFFECTORS = {"panda_hand_tcp": "panda_hand"}


def shipped_robots_dir() -> Path:
    """The folder of shipped descriptions: inside the installed package, else the source tree's robots/."""
    package = Path(__file__).resolve().parent.parent
    installed = package / "robots"
    return installed if installed.is_dir() else package.parent / "robots"


@lru_cache(maxsize=1)
def _shipped() -> dict[str, CatalogEntry]:
    entries: dict[str, CatalogEntry] = {}
    for urdf in sorted(shipped_robots_dir().glob("*/*.urdf")):
        if urdf.stem == urdf.parent.name:
            entries[urdf.stem] = CatalogEntry(
                urdf.stem, urdf, _SHIPPED_END_EFFECTORS.get(urdf.stem), "kinengine"
            )
    return entries


@lru_cache(maxsize=1)
def _entries() -> dict[str, CatalogEntry]:
    import importlib.metadata  # here, not at the top: ~15 ms of imports (email, zipfile, csv)

    entries = dict(_shipped())
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return entries
    root = Path(str(dist.locate_file(_ERD_PREFIX)))  # a path-like SimplePath, a Path in practice
    for name, (rel, ee) in _ERD_ROBOTS.items():
        path = root / rel
        if path.is_file():
            if ee in _FALLBACK_END_EFFECTORS and f'"{ee}"'.encode() not in path.read_bytes():
                ee = _FALLBACK_END_EFFECTORS[ee]
            entries[name] = CatalogEntry(
                name, path, ee, "example-robot-data", _LOCKED.get(name, ()), _EXTRA_COORDINATES.get(name, ())
            )
    return entries


def available_robots() -> list[str]:
    """Sorted short names that :func:`kinengine.load` accepts (shipped and example-robot-data)."""
    return sorted(_entries())


def find_entry(name: str) -> CatalogEntry | None:
    """The catalog entry of a short robot name, None if there is none. Only a name that example-robot-data
    may provide (and that it then provides instead of a shipped file) makes it look for example-robot-data."""
    return _entries().get(name) if name in _ERD_ROBOTS else _shipped().get(name)


def catalog_entry(name: str) -> CatalogEntry:
    """The catalog entry of a short robot name; URDFError listing the known names otherwise."""
    entry = find_entry(name)
    if entry is None:
        raise URDFError(
            f"unknown robot {name!r}: pass a path to a .urdf file or one of {', '.join(available_robots())}"
        )
    return entry
