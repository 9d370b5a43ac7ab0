"""The Robot's pictures: a matplotlib skeleton (:meth:`plot`) and the browser viewer (:meth:`view`); their
libraries are imported only when asked for."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, cast

from ..arrays import ArrayLike

if TYPE_CHECKING:
    import matplotlib.axes

    from ..presentation.viewer import Viewer
    from ..robot import Robot


class PresentationMethods:
    """Pictures of the robot at a configuration."""

    # -- presentation ---------------------------------------------------------------------------
    def plot(
        self,
        q: ArrayLike | None = None,
        ax: matplotlib.axes.Axes | None = None,
        *,
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        axis_length: float | None = None,
        title: bool | str = True,
    ) -> matplotlib.axes.Axes:
        """A matplotlib 3D picture of the robot at q (None: neutral); returns the axes. See
        :func:`kinengine.presentation.plotting.plot_robot`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        from ..presentation.plotting import plot_robot  # matplotlib only when asked for

        return plot_robot(
            robot, q, ax, frames=frames, ellipsoid=ellipsoid, axis_length=axis_length, title=title
        )

    def view(
        self,
        q: ArrayLike | None = None,
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
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        from ..presentation.viewer import view  # viser only when asked for

        return view(
            robot,
            q,
            port=port,
            host=host,
            frames=frames,
            ellipsoid=ellipsoid,
            parameterization=parameterization,
            meshes=meshes,
        )
