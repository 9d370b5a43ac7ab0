"""Viser scene nodes and GUI text of the browser viewer: URDF visuals as nodes, node poses, the χ readout.

Owns the translation between :mod:`.viewer_scene`'s data (root link frame I or link frames, lengths in m)
and what Viser draws: primitives and meshes placed at T_LV, node poses (position [m], unit quaternion
w, x, y, z) back to T (4, 4), and the HTML of the pose-parameter readout. Imported only by :mod:`.viewer`,
after the optional ``viser`` package was found.
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from . import viewer_scene as scene


def add_visual(server: Any, name: str, v: scene.Visual) -> None:
    """Add ``v`` to Viser ``server``'s scene as node ``name`` (a child of its link's node), at T_LV."""
    wxyz, position = scene.wxyz(v.origin[:3, :3]), v.origin[:3, 3]
    color = v.color or scene.DEFAULT_COLOR
    if v.kind == "box":
        server.scene.add_box(name, color=color, dimensions=v.size, wxyz=wxyz, position=position)
    elif v.kind == "cylinder":
        server.scene.add_cylinder(
            name, radius=v.size[0], height=v.size[1], color=color, wxyz=wxyz, position=position
        )
    elif v.kind == "sphere":
        server.scene.add_icosphere(name, radius=v.size[0], color=color, wxyz=wxyz, position=position)
    elif v.color is not None or getattr(v.mesh.visual, "kind", None) is None:  # mesh, URDF colour
        vertices, faces = np.asarray(v.mesh.vertices), np.asarray(v.mesh.faces)
        server.scene.add_mesh_simple(name, vertices, faces, color=color, wxyz=wxyz, position=position)
    else:  # the mesh's own colours or textures
        server.scene.add_mesh_trimesh(name, v.mesh, wxyz=wxyz, position=position)


def node_pose(node: Any) -> npt.NDArray[np.float64]:
    """T (4, 4) [m] of a Viser scene node from its ``position`` and unit quaternion ``wxyz``."""
    w, x, y, z = np.asarray(node.wxyz, dtype=float)
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = node.position
    return T


def readout_html(
    labels: Sequence[str], chi: np.ndarray, parameterization: str, distance: float, threshold: float
) -> str:
    """A table of χ (labels, values [m | rad]) and the distance to the parameterization's singular set,
    red (with the threshold) when below ``threshold``, green otherwise."""
    rows = "".join(
        f"<tr><td>{html.escape(str(label))}</td><td style='text-align:right'>{value:+.4f}</td></tr>"
        for label, value in zip(labels, chi, strict=True)
    )
    singular = distance < threshold
    color = "#d00000" if singular else "#208020"
    below = f" (below {threshold:g})" if singular else ""
    return (
        f"<table style='font-family:monospace;font-size:0.85em'>{rows}</table>"
        f"<div style='color:{color};font-size:0.85em'>distance to the {html.escape(parameterization)} "
        f"singularity: {distance:.3g}{below}</div>"
    )


__all__ = ["add_visual", "node_pose", "readout_html"]
