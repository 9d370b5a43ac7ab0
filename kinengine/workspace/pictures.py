"""Pictures of workspace maps (matplotlib, imported only when a picture is drawn)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import numpy.typing as npt

from ..presentation.plotting import pyplot


def reachability_slice(
    centers: npt.NDArray[np.float64],
    index: npt.NDArray[np.float64],
    voxel: float,
    z: float,
    title: str,
    path: str | os.PathLike[str] | None,
) -> Any:
    """One layer of a reachability map seen from above: a square per voxel, coloured by index [0, 1]."""
    plt = pyplot(headless=path is not None)
    fig, ax = plt.subplots(figsize=(6, 5.2))
    shown = index > 0
    if np.any(shown):
        art = ax.scatter(
            centers[shown, 0],
            centers[shown, 1],
            c=index[shown],
            cmap="RdYlGn",
            vmin=0.0,
            vmax=1.0,
            marker="s",
            s=1.0,
            linewidths=0,
        )
        fig.canvas.draw()  # marker size in points² from the voxel's size in data units
        (x0, _), (x1, _) = ax.transData.transform([(0.0, 0.0), (voxel, 0.0)])
        art.set_sizes([(abs(x1 - x0) * 72.0 / fig.dpi) ** 2])
        fig.colorbar(art, ax=ax, label="reachability index (fraction of orientations reached)")
    if len(centers):
        pad = voxel
        ax.set_xlim(centers[:, 0].min() - pad, centers[:, 0].max() + pad)
        ax.set_ylim(centers[:, 1].min() - pad, centers[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (root link frame)")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{title}: layer z = {z:.3f} m, voxel {voxel} m", fontsize=9)
    if path is not None:
        fig.savefig(os.fspath(path), dpi=120, bbox_inches="tight")
    return fig
