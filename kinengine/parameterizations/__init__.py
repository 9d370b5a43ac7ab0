"""End-effector parameterizations χ_e = (χ_P, χ_R) and their rate maps E.

Robot Dynamics lecture notes, ETH Zurich, section 2.8 (Kinematics of Systems of Bodies): task-space
coordinates (2.8.2) and the relation between geometric and analytic Jacobians (2.8.6).

χ̇_P = E_P(χ_P)·v and χ̇_R = E_R(χ_R)·ω, v and ω in the inertial (root) frame; J_A = blockdiag(E_P, E_R)·J_e0.

>>> from kinengine.parameterizations import get_rotation
>>> zyx = get_rotation("euler_zyx")
>>> chi = zyx.from_rotation(C_IE)        # (3,) [rad], like Rotation.from_matrix(C_IE).as_euler("ZYX")
>>> chi_dot = zyx.E(chi) @ omega         # omega [rad/s] in the inertial frame
"""

from __future__ import annotations

from ..errors import ParameterizationError
from .angle_axis import AngleAxis
from .base import Parameterization, PositionParameterization, RotationParameterization
from .cartesian import Cartesian
from .cylindrical import Cylindrical
from .euler import EULER_SEQUENCES, EulerAngles, EulerZYX
from .quaternion import Quaternion
from .rotation_matrix import RotationMatrix
from .rotation_vector import RotationVector
from .spherical import Spherical

POSITION_PARAMETERIZATIONS: dict[str, PositionParameterization] = {
    p.name: p for p in (Cartesian(), Cylindrical(), Spherical())
}
ROTATION_PARAMETERIZATIONS: dict[str, RotationParameterization] = {
    p.name: p
    for p in (
        *(EulerZYX() if seq == "zyx" else EulerAngles(seq) for seq in EULER_SEQUENCES),
        Quaternion(),
        AngleAxis(),
        RotationVector(),
        RotationMatrix(),
    )
}


def get_position(name: str) -> PositionParameterization:
    """The position parameterization called ``name``; ParameterizationError listing the valid names."""
    try:
        return POSITION_PARAMETERIZATIONS[name]
    except (KeyError, TypeError):
        raise ParameterizationError.unknown("position", name, list(POSITION_PARAMETERIZATIONS)) from None


def get_rotation(name: str) -> RotationParameterization:
    """The rotation parameterization called ``name``; ParameterizationError listing the valid names."""
    try:
        return ROTATION_PARAMETERIZATIONS[name]
    except (KeyError, TypeError):
        raise ParameterizationError.unknown("rotation", name, list(ROTATION_PARAMETERIZATIONS)) from None


def parameter_labels(position: str | None, rotation: str | None) -> tuple[str, ...]:
    """Row labels of χ = (χ_P, χ_R) for the named parameterizations (None leaves a part out)."""
    p = () if position is None else tuple(get_position(position).labels)
    return p + (() if rotation is None else tuple(get_rotation(rotation).labels))


__all__ = [
    "EULER_SEQUENCES",
    "POSITION_PARAMETERIZATIONS",
    "ROTATION_PARAMETERIZATIONS",
    "AngleAxis",
    "Cartesian",
    "Cylindrical",
    "EulerAngles",
    "EulerZYX",
    "Parameterization",
    "PositionParameterization",
    "Quaternion",
    "RotationMatrix",
    "RotationParameterization",
    "RotationVector",
    "Spherical",
    "get_position",
    "get_rotation",
    "parameter_labels",
]
