"""The Robot's pictures: a matplotlib skeleton (:meth:`plot`) and the browser viewer (:meth:`view`); their
libraries are imported only when asked for."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import matplotlib.axes

    from ..presentation.viewer import Viewer
    from ..robot import Robot


class PresentationMethods:
    """Pictures of the robot at a configuration."""

    # -- presentation ---------------------------------------------------------------------------
    def plot(
        self: Robot,
        q: object = None,
        ax: object = None,
        *,
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        axis_length: float | None = None,
        title: bool | str = True,
    ) -> matplotlib.axes.Axes:
        """A matplotlib 3D picture of the robot at q (None: neutral); returns the axes. See
        :func:`kinengine.presentation.plotting.plot_robot`."""
        from ..presentation.plotting import plot_robot  # matplotlib only when asked for

        return plot_robot(
            self, q, ax, frames=frames, ellipsoid=ellipsoid, axis_length=axis_length, title=title
        )

    def view(
        self: Robot,
        q: object = None,
        *,
        port: int | None = None,
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        parameterization: str = "euler_zyx",
        meshes: bool = True,
        host: str = "127.0.0.1",
    ) -> Viewer:
        """Serve the robot at q (None: neutral) in the browser (Viser); returns the running viewer:
        ``.url``, ``.update(q)`` (moves the robot live), ``.close()``. Needs
        ``pip install 'kinengine[view]'``. See :func:`kinengine.presentation.viewer.view`."""
        from ..presentation.viewer import view  # viser only when asked for

        return view(
            self,
            q,
            port=port,
            host=host,
            frames=frames,
            ellipsoid=ellipsoid,
            parameterization=parameterization,
            meshes=meshes,
        )
